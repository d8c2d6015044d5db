//! The Rust generator: a `no_std` module built with proc-macro2 + quote and
//! formatted with prettyplease. It declares the tables as `static` data for
//! `tsf_runtime::Controller` and wraps them in a small `Controller` struct.
//! The generated file is meant to be `include!`d (no inner attributes).

use super::sym::{Func, Sym};
use super::tables::{PremiseCode, Tables};
use crate::model::TermSpec;
use proc_macro2::{Ident, Literal, Span, TokenStream};
use quote::{format_ident, quote};
use tsf_lang::spec::{Precision, SetShape};

/// A float literal of the table's precision (shortest round-trip form;
/// negatives as a unary minus; infinities as the type's constant).
fn float(v: f64, prec: Precision) -> TokenStream {
    let ty = real_ty(prec);
    if v.is_infinite() {
        return if v > 0.0 {
            quote!(#ty::INFINITY)
        } else {
            quote!(#ty::NEG_INFINITY)
        };
    }
    if v.is_nan() {
        return quote!(#ty::NAN);
    }
    let lit = match prec {
        Precision::F64 => Literal::f64_unsuffixed(v.abs()),
        Precision::F32 => Literal::f32_unsuffixed((v as f32).abs()),
    };
    if v.is_sign_negative() && v != 0.0 {
        quote!(-#lit)
    } else {
        quote!(#lit)
    }
}

fn real_ty(prec: Precision) -> Ident {
    Ident::new(
        if prec == Precision::F32 { "f32" } else { "f64" },
        Span::call_site(),
    )
}

fn array(values: &[f64], prec: Precision) -> TokenStream {
    let items = values.iter().map(|v| float(*v, prec));
    quote!([#(#items),*])
}

fn matrix(rows: &[Vec<f64>], prec: Precision) -> TokenStream {
    let items = rows.iter().map(|r| array(r, prec));
    quote!([#(#items),*])
}

fn membership(s: &SetShape, prec: Precision) -> TokenStream {
    let f = |v: f64| float(v, prec);
    match *s {
        SetShape::Tri(a, b, c) => {
            let (a, b, c) = (f(a), f(b), f(c));
            quote!(Membership::Tri { a: #a, b: #b, c: #c })
        }
        SetShape::Trap(a, b, c, d) => {
            let (a, b, c, d) = (f(a), f(b), f(c), f(d));
            quote!(Membership::Trap { a: #a, b: #b, c: #c, d: #d })
        }
        SetShape::Gauss(center, sigma) => {
            let (c, s) = (f(center), f(sigma));
            quote!(Membership::Gauss { center: #c, sigma: #s })
        }
        SetShape::Sigmoid(slope, center) => {
            let (k, c) = (f(slope), f(center));
            quote!(Membership::Sigmoid { slope: #k, center: #c })
        }
    }
}

/// Scalar code for a premise expression; `x` is the state array. Parentheses
/// only where precedence needs them (the tree's grouping is kept exactly, so
/// the C generator's code performs the same operations in the same order).
fn sym(s: &Sym, prec: Precision) -> TokenStream {
    sym_in(s, prec, 0)
}

/// Binding strength of a node: sums 1, products 2, negation 3, atoms 4.
fn strength(s: &Sym) -> u8 {
    match s {
        Sym::Add(..) => 1,
        Sym::Mul(..) | Sym::Div(..) => 2,
        Sym::Neg(_) => 3,
        Sym::Const(v) if *v < 0.0 => 3,
        _ => 4,
    }
}

fn sym_in(s: &Sym, prec: Precision, parent: u8) -> TokenStream {
    let inner = match s {
        Sym::Const(v) => float(*v, prec),
        Sym::X(k) => {
            let k = Literal::usize_unsuffixed(*k);
            quote!(x[#k])
        }
        Sym::Add(a, b) => {
            let (a, b) = (sym_in(a, prec, 1), sym_in(b, prec, 2));
            quote!(#a + #b)
        }
        Sym::Mul(a, b) => {
            let (a, b) = (sym_in(a, prec, 2), sym_in(b, prec, 3));
            quote!(#a * #b)
        }
        Sym::Div(a, b) => {
            let (a, b) = (sym_in(a, prec, 2), sym_in(b, prec, 3));
            quote!(#a / #b)
        }
        Sym::Neg(a) => {
            let a = sym_in(a, prec, 4);
            quote!(-#a)
        }
        Sym::Call(f, a) => {
            let a = sym_in(a, prec, 0);
            let name = match f {
                Func::Abs => format_ident!("abs"),
                other => format_ident!("{}", other.name()),
            };
            quote!(Real::#name(#a))
        }
    };
    if strength(s) < parent {
        quote!((#inner))
    } else {
        inner
    }
}

/// The generated module's text.
pub fn emit_rust(t: &Tables) -> Result<String, String> {
    let prec = t.precision;
    let ty = real_ty(prec);
    let (n, m, p, r) = (
        Literal::usize_unsuffixed(t.n),
        Literal::usize_unsuffixed(t.m),
        Literal::usize_unsuffixed(t.p),
        Literal::usize_unsuffixed(t.r),
    );
    // Rule premises: one static term array per rule (and point arrays for `about`).
    let mut statics = Vec::new();
    let mut rule_refs = Vec::new();
    for (ri, terms) in t.terms.iter().enumerate() {
        let terms_ident = format_ident!("TERMS_{}", ri + 1);
        let mut items = Vec::new();
        for (ti, term) in terms.iter().enumerate() {
            match term {
                TermSpec::Is { var, set } => {
                    let var = Literal::usize_unsuffixed(*var);
                    let set = membership(set, prec);
                    items.push(quote!(Term::Is { var: #var, set: #set }));
                }
                TermSpec::About {
                    first,
                    point,
                    sigma,
                } => {
                    let pt = format_ident!("POINT_{}_{}", ri + 1, ti + 1);
                    let len = Literal::usize_unsuffixed(point.len());
                    let vals = array(point, prec);
                    statics.push(quote! {
                        #[allow(clippy::approx_constant, clippy::excessive_precision)]
                        static #pt: [#ty; #len] = #vals;
                    });
                    let first = Literal::usize_unsuffixed(*first);
                    let sigma = float(*sigma, prec);
                    items.push(quote!(Term::About { first: #first, point: &#pt, sigma: #sigma }));
                }
            }
        }
        let count = Literal::usize_unsuffixed(items.len());
        let doc = format!(
            "Premise of rule {}.",
            t.rule_names.get(ri).map_or("?", String::as_str)
        );
        statics.push(quote! {
            #[doc = #doc]
            #[allow(clippy::approx_constant, clippy::excessive_precision)]
            static #terms_ident: [Term<'static, #ty>; #count] = [#(#items),*];
        });
        rule_refs.push(quote!(Rule::new(&#terms_ident)));
    }
    let (premise_map, step_body, premise_fn) = match &t.premise {
        PremiseCode::Linear(l) => (matrix(l, prec), quote!(TABLE.step(x)), quote!()),
        PremiseCode::Exprs(exprs) => {
            let zero_rows: Vec<Vec<f64>> = (0..t.p).map(|_| vec![0.0; t.n]).collect();
            let items = exprs.iter().map(|e| sym(e, prec));
            (
                matrix(&zero_rows, prec),
                quote!(TABLE.step_with_premises(x, &premises(x))),
                quote! {
                    /// The premise variables z as functions of the state (from the spec).
                    #[allow(clippy::approx_constant, clippy::excessive_precision)]
                    pub fn premises(x: &[#ty; N]) -> [#ty; P] {
                        [#(#items),*]
                    }
                },
            )
        }
    };
    let centres = matrix(&t.centres, prec);
    let gains = {
        let items = t.gains.iter().map(|g| matrix(g, prec));
        quote!([#(#items),*])
    };
    let u_max = array(&t.u_max, prec);
    let state_doc = format!("State order: {}.", t.state_names.join(", "));
    let input_doc = format!("Input order: {}.", t.input_names.join(", "));
    let uses_real = matches!(t.premise, PremiseCode::Exprs(_));
    let uses_membership = t
        .terms
        .iter()
        .flatten()
        .any(|x| matches!(x, TermSpec::Is { .. }));
    let mut imports = vec![quote!(Flags)];
    if uses_membership {
        imports.push(quote!(Membership));
    }
    if uses_real {
        imports.push(quote!(Real));
    }
    imports.push(quote!(Rule));
    imports.push(quote!(Term));
    let tokens = quote! {
        use tsf_runtime::{#(#imports),*};

        /// Number of states.
        pub const N: usize = #n;
        /// Number of inputs.
        pub const M: usize = #m;
        /// Number of premise variables.
        pub const P: usize = #p;
        /// Number of rules.
        pub const R: usize = #r;

        #(#statics)*

        /// The controller's tables, certified by tsfc.
        #[allow(clippy::approx_constant, clippy::excessive_precision, clippy::unreadable_literal)]
        pub static TABLE: tsf_runtime::Controller<'static, #ty, N, M, P, R> = tsf_runtime::Controller {
            premise_map: #premise_map,
            rules: [#(#rule_refs),*],
            centres: #centres,
            gains: #gains,
            u_max: #u_max,
        };

        #premise_fn

        /// The T-S PDC controller: u = sat(sum_j h_j(z) F_j x).
        #[doc = #state_doc]
        #[doc = #input_doc]
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct Controller {
            flags: Flags,
            strengths: [#ty; R],
        }

        impl Controller {
            /// Number of states.
            pub const N: usize = N;
            /// Number of inputs.
            pub const M: usize = M;
            /// Number of rules.
            pub const R: usize = R;

            /// A controller with no step taken yet.
            pub const fn new() -> Self {
                Controller { flags: Flags::NONE, strengths: [0.0; R] }
            }

            /// One control update: the saturated command for state `x`.
            /// Never panics; NaN or infinite states give a zero command and a fault flag.
            pub fn step(&mut self, x: &[#ty; N]) -> [#ty; M] {
                let s = #step_body;
                self.flags = s.flags;
                self.strengths = s.h;
                s.u
            }

            /// Flags of the last step.
            pub fn flags(&self) -> Flags {
                self.flags
            }

            /// Whether the last step saw a NaN or infinite state (command forced to zero).
            pub fn fault(&self) -> bool {
                self.flags.is_fault()
            }

            /// Whether no rule fired in the last step (nearest rule's gain used).
            pub fn no_rule_fired(&self) -> bool {
                self.flags.contains(Flags::NO_RULE_FIRED)
            }

            /// Whether a channel was clipped in the last step.
            pub fn saturated(&self) -> bool {
                self.flags.contains(Flags::SATURATED)
            }

            /// Normalised firing strengths of the last step.
            pub fn strengths(&self) -> &[#ty; R] {
                &self.strengths
            }
        }

        impl Default for Controller {
            fn default() -> Self {
                Self::new()
            }
        }
    };
    let file: syn::File = syn::parse2(tokens)
        .map_err(|e| format!("internal error: generated Rust does not parse: {e}"))?;
    let body = prettyplease::unparse(&file);
    Ok(format!("{}{body}", header(t)))
}

/// The header comment (no timestamps, no absolute paths).
fn header(t: &Tables) -> String {
    let h = &t.header;
    let mut s = format!(
        "// @generated by tsfc {} from {} (sha256 {})\n// Do not edit: regenerate with `tsfc compile`.\n//\n// Controller `{}`: {} states, {} inputs, {} rules, {} premise variables; relaxation {}.\n",
        h.tsfc_version, h.spec_path, h.spec_sha256, t.name, t.n, t.m, t.r, t.p, h.relaxation
    );
    for (k, v) in &h.objectives {
        s.push_str(&format!("// {k} = {v}\n"));
    }
    s.push_str(&format!(
        "// certificate: every LMI holds; minimum margin {:.3e}\n\n",
        h.min_margin
    ));
    s
}
