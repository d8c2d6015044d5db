//! The rule premises factored into distinct terms: every `(premise, set)`
//! pair (or `about` term) once, and each rule as indices into that list, so
//! generated code evaluates each membership once per step.

use crate::model::TermSpec;

/// Distinct premise terms and the rules over them.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FactoredTerms {
    /// The distinct terms, in order of first use (rule by rule, term by term).
    pub terms: Vec<TermSpec>,
    /// Each rule's premise: indices into `terms`, in the rule's term order.
    pub rules: Vec<Vec<usize>>,
}

impl FactoredTerms {
    /// Factors the rule premises `rules` (one list of terms per rule). Terms
    /// that compare equal are one entry (equal parameters give equal degrees;
    /// a NaN parameter never compares equal, so such a term is kept apart).
    pub fn new(rules: &[Vec<TermSpec>]) -> Self {
        let mut out = FactoredTerms::default();
        for rule in rules {
            let indices = rule
                .iter()
                .map(|term| match out.terms.iter().position(|t| t == term) {
                    Some(k) => k,
                    None => {
                        out.terms.push(term.clone());
                        out.terms.len() - 1
                    }
                })
                .collect();
            out.rules.push(indices);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tsf_lang::spec::SetShape;

    fn is(var: usize, a: f64) -> TermSpec {
        TermSpec::Is {
            var,
            set: SetShape::Tri(a, a + 1.0, a + 2.0),
        }
    }

    #[test]
    fn shared_terms_are_listed_once_in_order_of_first_use() {
        let rules = vec![
            vec![is(0, 0.0), is(1, 0.0)],
            vec![is(0, 0.0), is(1, 5.0)],
            vec![is(0, 5.0), is(1, 0.0)],
            vec![],
        ];
        let f = FactoredTerms::new(&rules);
        assert_eq!(
            f.terms,
            vec![is(0, 0.0), is(1, 0.0), is(1, 5.0), is(0, 5.0)]
        );
        assert_eq!(f.rules, vec![vec![0, 1], vec![0, 2], vec![3, 1], vec![]]);
        // Same set on another premise component: a different term.
        let g = FactoredTerms::new(&[vec![is(0, 0.0)], vec![is(1, 0.0)]]);
        assert_eq!(g.terms.len(), 2);
        let nan = TermSpec::Is {
            var: 0,
            set: SetShape::Gauss(f64::NAN, 1.0),
        };
        let h = FactoredTerms::new(&[vec![nan.clone()], vec![nan]]);
        assert_eq!(h.rules, vec![vec![0], vec![1]], "NaN never compares equal");
    }
}
