//! The Rust generator: a `no_std` module built with proc-macro2 + quote and
//! formatted with prettyplease. It declares the tables as `static` data for
//! `tsf_runtime::Controller` and wraps them in a small `Controller` struct.
//! The generated file is meant to be `include!`d (no inner attributes).

use super::header::{law_summary, marker, sensor_certificate, sensor_name};
use super::{Backend, CodegenError, GeneratedFile};
use crate::model::TermSpec;
use crate::tables::sym::{Func, Sym};
use crate::tables::{PremiseCode, SensorLaw, SensorTables, Tables};
use proc_macro2::{Ident, Literal, Span, TokenStream};
use quote::{format_ident, quote};
use tsf_lang::spec::{Emit, Precision, SetShape};

/// The Rust backend: `<name>.rs`, and `<name>_sensor.rs` for an aperiodic
/// event trigger.
#[derive(Debug, Clone, Copy)]
pub struct RustBackend;

impl Backend for RustBackend {
    fn target(&self) -> Emit {
        Emit::Rust
    }

    fn files(&self, t: &Tables) -> Result<Vec<GeneratedFile>, CodegenError> {
        let mut out = vec![GeneratedFile {
            name: format!("{}.rs", t.name),
            text: emit_rust(t)?,
        }];
        if t.trigger.is_some() {
            out.push(GeneratedFile {
                name: format!("{}.rs", sensor_name(t)),
                text: emit_rust_sensor(t)?,
            });
        }
        Ok(out)
    }
}

/// Formats the generated tokens (an error names a generator bug).
fn unparse(tokens: TokenStream) -> Result<String, CodegenError> {
    let file: syn::File = syn::parse2(tokens).map_err(|e| CodegenError::Unparsable {
        language: "Rust",
        reason: e.to_string(),
    })?;
    Ok(prettyplease::unparse(&file))
}

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
pub fn emit_rust(t: &Tables) -> Result<String, CodegenError> {
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
    let body = unparse(tokens)?;
    Ok(format!("{}{body}", header(t)))
}

/// The header comment (no timestamps, no absolute paths).
fn header(t: &Tables) -> String {
    let h = &t.header;
    let mut s = marker(h);
    s.push_str(&format!(
        "// Controller `{}`: {} states, {} inputs, {} rules, {} premise variables; relaxation {}.\n",
        t.name, t.n, t.m, t.r, t.p, h.relaxation
    ));
    if t.trigger.is_some() {
        s.push_str(&format!(
            "// Controller-side role of the event-triggered loop: `step` is fed the received x(t_k),\n// the last state transmitted by the sensor module `{}`; memberships\n// and feedback are evaluated at x(t_k), and the command is held between transmissions.\n",
            sensor_name(t)
        ));
    }
    for (k, v) in &h.objectives {
        s.push_str(&format!("// {k} = {v}\n"));
    }
    s.push_str(&format!(
        "// certificate: every LMI holds; minimum margin {:.3e}\n\n",
        h.min_margin
    ));
    s
}

/// The sensor-side trigger module `<controller>_sensor.rs`: decides at each
/// sampling instant whether to transmit the state, holds the last transmitted
/// state and the threshold. Errors if the design has no trigger.
pub fn emit_rust_sensor(t: &Tables) -> Result<String, CodegenError> {
    let s = t.trigger.as_ref().ok_or(CodegenError::NoSensor)?;
    let prec = t.precision;
    let ty = real_ty(prec);
    let n = Literal::usize_unsuffixed(t.n);
    let (h_min, h_max) = (float(s.h_min, prec), float(s.h_max, prec));
    let (nu_min, nu_max) = (float(s.nu_min, prec), float(s.nu_max, prec));
    let weight = matrix(&s.weight, prec);
    let range_doc = format!(
        "The threshold nu(t_k) stays in [NU_MIN, NU_MAX] = [{:?}, {:?}]; {}.",
        s.nu_min,
        s.nu_max,
        match s.certified {
            Some((nu, _)) => format!("the event-triggered loop is certified for nu(t_k) <= {nu:?}"),
            None => "tsfc did not certify the event-triggered loop with this weight".into(),
        }
    );
    let sampling_doc = format!(
        "Call [`Sensor::sample`] at every sampling instant t_k^l, with intervals \
         t_k^(l+1) - t_k^l in [H_MIN, H_MAX] = [{:?}, {:?}] s.",
        s.h_min, s.h_max
    );
    let state_doc = format!("State order: {}.", t.state_names.join(", "));
    let controller_doc = format!(
        "Feed every transmitted state to the controller module `{}` (`Controller::step`), \
         which holds its command until the next transmission.",
        t.name
    );
    let (law_use, law_items, field, init, nu_body, last_body, law_doc) = match s.law {
        SensorLaw::Adaptive(mu1, mu2, mu3) => {
            let (mu1, mu2, mu3) = (float(mu1, prec), float(mu2, prec), float(mu3, prec));
            (
                quote!(
                    use tsf_runtime::AdaptiveTrigger;
                ),
                quote! {
                    /// Gain mu1 of the adaptive law.
                    #[allow(clippy::approx_constant, clippy::excessive_precision)]
                    pub const MU1: #ty = #mu1;
                    /// Slope mu2 inside the atan of the adaptive law.
                    #[allow(clippy::approx_constant, clippy::excessive_precision)]
                    pub const MU2: #ty = #mu2;
                    /// Jump size mu3 at which the adaptive law keeps nu constant.
                    #[allow(clippy::approx_constant, clippy::excessive_precision)]
                    pub const MU3: #ty = #mu3;
                },
                quote!(trigger: AdaptiveTrigger<#ty, N>),
                quote!(trigger: AdaptiveTrigger::new(WEIGHT, NU_MIN, MU1, MU2, MU3).with_max(NU_MAX)),
                quote!(self.trigger.nu()),
                quote!(self.trigger.last()),
                "Transmit iff e'U e >= nu(t_k) x(t_k)'U x(t_k), e = x - x(t_k); after each \
                 transmission nu(t_(k+1)) = min(max(nu(t_k) (1 - (2 MU1/pi) atan(MU2 \
                 (||x(t_(k+1)) - x(t_k)|| - MU3))), NU_MIN), NU_MAX), nu(0) = NU_MIN \
                 (tsf_runtime::AdaptiveTrigger with `with_max(NU_MAX)`).",
            )
        }
        SensorLaw::Relative => (
            quote!(
                use tsf_runtime::RelativeTrigger;
            ),
            quote!(),
            quote!(trigger: RelativeTrigger<#ty, N>),
            quote!(trigger: RelativeTrigger::new(WEIGHT, NU_MIN)),
            quote!(self.trigger.nu),
            quote!(self.trigger.last()),
            "Transmit iff e'U e >= NU_MIN x(t_k)'U x(t_k), e = x - x(t_k) \
             (tsf_runtime::RelativeTrigger).",
        ),
        SensorLaw::EverySample => (
            quote!(),
            quote!(),
            quote!(last: Option<[#ty; N]>),
            quote!(last: None),
            quote!(NU_MIN),
            quote!(self.last.as_ref()),
            "No threshold: every sample is transmitted.",
        ),
    };
    let sample_body = match s.law {
        SensorLaw::EverySample => quote! {
            self.last = Some(*x);
            Some(*x)
        },
        _ => quote! {
            if self.trigger.decide(x) {
                Some(*x)
            } else {
                None
            }
        },
    };
    // One paragraph per line (a leading space, as `///` comments have).
    let mut docs = Vec::new();
    for (k, line) in [
        "Sensor-side event trigger: decides at each sampling instant whether to transmit \
         the state, and holds the last transmitted state x(t_k) and the threshold nu(t_k).",
        law_doc,
        &range_doc,
        &sampling_doc,
        &controller_doc,
        &state_doc,
    ]
    .into_iter()
    .enumerate()
    {
        if k > 0 {
            docs.push(String::new());
        }
        docs.push(format!(" {line}"));
    }
    let nu_max_doc = match s.certified {
        Some(_) => " Ceiling of the threshold: the value the loop is certified for.",
        None => " Ceiling of the threshold (the event-triggered loop was not certified by tsfc).",
    };
    let tokens = quote! {
        #law_use

        /// Number of states.
        pub const N: usize = #n;
        /// Shortest sampling interval h_min (s).
        #[allow(clippy::approx_constant, clippy::excessive_precision)]
        pub const H_MIN: #ty = #h_min;
        /// Longest sampling interval h_max (s).
        #[allow(clippy::approx_constant, clippy::excessive_precision)]
        pub const H_MAX: #ty = #h_max;
        /// Lower bound and initial value nu(0) of the threshold.
        #[allow(clippy::approx_constant, clippy::excessive_precision)]
        pub const NU_MIN: #ty = #nu_min;
        #[doc = #nu_max_doc]
        #[allow(clippy::approx_constant, clippy::excessive_precision)]
        pub const NU_MAX: #ty = #nu_max;
        #law_items
        /// Trigger weight U (symmetric positive semidefinite), rows in state order.
        #[allow(clippy::approx_constant, clippy::excessive_precision, clippy::unreadable_literal)]
        pub const WEIGHT: [[#ty; N]; N] = #weight;

        #(#[doc = #docs])*
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct Sensor {
            #field,
        }

        impl Sensor {
            /// Number of states.
            pub const N: usize = N;

            /// A sensor that has transmitted nothing yet (nu = NU_MIN); the
            /// first sample is always transmitted.
            pub const fn new() -> Self {
                Sensor { #init }
            }

            /// Decides at a sampling instant: `Some(x)` if `x` is transmitted
            /// now (it becomes x(t_k)), `None` otherwise. Never panics; a
            /// comparison involving NaN transmits.
            pub fn sample(&mut self, x: &[#ty; N]) -> Option<[#ty; N]> {
                #sample_body
            }

            /// Current threshold nu(t_k), in [NU_MIN, NU_MAX].
            pub fn nu(&self) -> #ty {
                #nu_body
            }

            /// Last transmitted state x(t_k), if any.
            pub fn last(&self) -> Option<&[#ty; N]> {
                #last_body
            }
        }

        impl Default for Sensor {
            fn default() -> Self {
                Self::new()
            }
        }
    };
    let body = unparse(tokens)?;
    Ok(format!("{}{body}", sensor_header(t, s)))
}

/// Header comment of the sensor module.
fn sensor_header(t: &Tables, s: &SensorTables) -> String {
    let mut out = marker(&t.header);
    out.push_str(&format!(
        "// Sensor-side event trigger of controller `{}` ({} states): at each sampling instant\n\
         // (intervals in [{:?}, {:?}] s) decides whether to transmit x; the controller module\n\
         // `{}` is fed the transmitted x(t_k).\n\
         // Law: {}.\n// Weight U: {}.\n// certificate: {}.\n\n",
        t.name,
        t.n,
        s.h_min,
        s.h_max,
        t.name,
        law_summary(s),
        s.weight_source,
        sensor_certificate(t, s),
    ));
    out
}
