//! Hover texts: a constant's value and shape, a matrix's shape, a fuzzy set's
//! parameters, a rule's local model at its operating point (as `tsfc check
//! --explain` prints it), a signal's place in x, u or w, and an objective's
//! meaning in one line.

use super::document::Document;
use super::symbols::{Decl, Kind};
use crate::model::explain;
use crate::model::TsModel;
use nalgebra::DMatrix;
use tsf_lang::ast::ItemKind;
use tsf_lang::num::Num;
use tsf_lang::spec::{SetShape, Signal};

/// Largest matrix (elements) whose entries a hover prints; larger ones show their shape.
const MAX_SHOWN_ELEMENTS: usize = 144;

/// Longest piece of the declaration's text a hover repeats (bytes).
const MAX_SNIPPET: usize = 240;

/// The objectives and their meaning in one line (from docs/language.md).
pub const OBJECTIVES: &[(&str, &str)] = &[
    ("stability", "V decreases along every trajectory (imposed whenever nothing else implies it)."),
    ("decay_rate", "`decay_rate >= a`: V(t) <= V(0) e^{-2 a t}."),
    ("hinf", "`hinf(w -> z) <= g`: |z|_2 < g |w|_2 from x(0) = 0, and stability."),
    ("linf", "`linf(w -> y) <= g`: |y|_inf < g |w|_inf from x(0) = 0 for the given or searched xi, phi."),
    ("input_norm", "`input_norm(u) <= mu for x0 ...`: |u(t)| <= mu for every x0 in the set (inside E(P, 1))."),
    ("output_norm", "`output_norm(z) <= l for x0 ...`: |z(t)| <= l for every x0 in the set."),
    ("saturation", "`saturation region [for x0 ...]`: E(P, 1) is invariant for the saturated loop and lies where the generalized sector condition holds (a region of attraction)."),
    ("finite_time", "`finite_time`: x(0)' R x(0) <= c1 and the energy bound imply E[x(t)' R x(t)] < c2 for every t in [0, T] (needs a `modes` block)."),
];

/// The hover text (Markdown) at byte `offset`, if there is something to say.
pub fn hover(doc: &Document, offset: usize) -> Option<String> {
    if let Some(text) = objective_at(doc, offset) {
        return Some(text);
    }
    let (_, decl) = doc.index.decl_at(offset)?;
    let mut out = format!("**{}** `{}`\n", decl.kind.word(), decl.name);
    let facts = doc
        .hover_model()
        .and_then(|(model, stale)| facts(model, decl).map(|f| (f, stale)));
    match facts {
        Some((f, stale)) => {
            out.push_str(&f);
            if stale {
                out.push_str("\n_(from the last version of the document that checked clean)_\n");
            }
        }
        None => {
            out.push_str(&format!(
                "```tsf\n{}\n```\n",
                doc.snippet(decl.item, MAX_SNIPPET)
            ));
        }
    }
    Some(out)
}

/// The meaning of the objective whose name is at `offset`.
fn objective_at(doc: &Document, offset: usize) -> Option<String> {
    doc.file.items.iter().find_map(|it| match &it.kind {
        ItemKind::Objective { name, .. }
            if name.span.start <= offset && offset <= name.span.end =>
        {
            let (_, line) = OBJECTIVES.iter().find(|(k, _)| *k == name.node)?;
            Some(format!("**objective** `{}`\n\n{line}\n", name.node))
        }
        _ => None,
    })
}

/// What the model knows about `decl` (values, shapes, local models).
fn facts(model: &TsModel, decl: &Decl) -> Option<String> {
    let spec = &model.spec;
    match decl.kind {
        Kind::Const => {
            let value = spec.consts.get(&decl.name).or_else(|| {
                let dynamics = spec.simulate.as_ref()?.dynamics.as_ref()?;
                dynamics
                    .consts
                    .iter()
                    .find(|(n, _)| *n == decl.name)
                    .map(|(_, m)| m)
            })?;
            Some(value_text(value))
        }
        Kind::State | Kind::Input | Kind::Disturbance => {
            let (list, vector, total): (&[Signal], &str, usize) = match decl.kind {
                Kind::State => (&spec.states, "x", model.n),
                Kind::Input => (&spec.inputs, "u", model.m),
                _ => (&spec.disturbances, "w", model.q),
            };
            let s = list.iter().find(|s| s.name == decl.name)?;
            let at = if s.len == 1 {
                format!("{vector}[{}]", s.offset)
            } else {
                format!("{vector}[{}..{}]", s.offset, s.offset + s.len)
            };
            Some(format!("\n{at} (of {total} components)\n"))
        }
        Kind::Matrix => {
            let (m, cols) = match decl.name.as_str() {
                "A" => (spec.a.as_ref(), (model.n, "n")),
                "B" => (spec.b.as_ref(), (model.m, "m")),
                "D" => (spec.d.as_ref(), (model.q, "q")),
                _ => return None,
            };
            let dep = if m?.state_dependent {
                ", depends on the state"
            } else {
                ""
            };
            Some(format!(
                "\n{} x {} (n x {}){dep}\n",
                model.n, cols.0, cols.1
            ))
        }
        Kind::Set => {
            let (p, set) = spec.premises.iter().find_map(|p| {
                let set = p.sets.iter().find(|s| s.name == decl.name)?;
                decl.premise.contains(&p.name).then_some((p, set))
            })?;
            Some(format!(
                "of premise `{}`\n```tsf\n{} = {}\n```\n{}\n",
                p.name,
                set.name,
                set.shape,
                shape_words(&set.shape)
            ))
        }
        Kind::Premise => {
            let p = spec.premises.iter().find(|p| p.name == decl.name)?;
            let range = p.range.map_or(String::new(), |(lo, hi)| {
                format!("range {} .. {}", Num(lo), Num(hi))
            });
            let sets: Vec<String> = p
                .sets
                .iter()
                .map(|s| format!("{} = {}", s.name, s.shape))
                .collect();
            Some(format!("\n{range}\n```tsf\n{}\n```\n", sets.join("\n")))
        }
        Kind::Rule => {
            let k = spec.rules.iter().position(|r| r.name == decl.name)?;
            let at = spec.rules[k].at.as_ref().map_or(String::new(), |(v, _)| {
                let v: Vec<String> = v.iter().map(|x| Num(*x).to_string()).collect();
                format!("operating point x = [{}]\n", v.join(", "))
            });
            Some(format!(
                "\n{at}local model as built:\n```\n{}```\n",
                explain::rule(model, k)
            ))
        }
        _ => None,
    }
}

/// A constant's shape and (when small) its entries.
fn value_text(m: &DMatrix<f64>) -> String {
    let shape = if m.nrows() == 1 && m.ncols() == 1 {
        "scalar".to_string()
    } else {
        format!("{} x {} matrix", m.nrows(), m.ncols())
    };
    if m.nrows() == 1 && m.ncols() == 1 {
        format!("\n= {} ({shape})\n", Num(m[(0, 0)]))
    } else if m.len() <= MAX_SHOWN_ELEMENTS {
        format!("\n{shape}\n```\n{}```\n", explain::matrix("value", m))
    } else {
        format!("\n{shape} (too large to show)\n")
    }
}

/// A shape's parameters in words.
fn shape_words(s: &SetShape) -> String {
    match *s {
        SetShape::Tri(a, b, c) => {
            format!("triangle: feet {} and {}, peak {}", Num(a), Num(c), Num(b))
        }
        SetShape::Trap(a, b, c, d) => format!(
            "trapezoid: feet {} and {}, plateau {} .. {}",
            Num(a),
            Num(d),
            Num(b),
            Num(c)
        ),
        SetShape::Gauss(c, s) => format!("Gaussian: center {}, sigma {}", Num(c), Num(s)),
        SetShape::Sigmoid(a, c) => format!("sigmoid: slope {}, center {}", Num(a), Num(c)),
    }
}
