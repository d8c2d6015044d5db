//! The Rust module of an adaptive controller (docs/adaptive.md): the tables
//! as a `static tsf_runtime::AdaptiveController` (premise map, rule terms,
//! centres, the law's C, A_m, P, rates, bounds and layer, the period), the
//! spec's initial estimates as constants, and a caller-owned `State` whose
//! `step` runs the runtime's law on it. No allocation, no panic: the module
//! only hands arrays to the runtime.

use super::tokens::{array, float, matrix};
use super::{dimension_consts, premise_imports, unparse, Premises, Rules};
use crate::codegen::header::generated_lines;
use crate::codegen::CodegenError;
use crate::tables::{AdaptiveTables, Tables};
use proc_macro2::{Literal, TokenStream};
use quote::quote;
use tsf_lang::spec::Precision;
use tsf_runtime::Adaptation;

/// `Adaptation { rate, lo, hi }`.
fn adaptation(a: &Adaptation) -> TokenStream {
    let (rate, lo, hi) = (
        float(a.rate, Precision::F64),
        float(a.lo, Precision::F64),
        float(a.hi, Precision::F64),
    );
    quote!(Adaptation { rate: #rate, lo: #lo, hi: #hi })
}

/// The generated module's text.
pub fn emit_rust_adaptive(at: &AdaptiveTables) -> Result<String, CodegenError> {
    let t = &at.base;
    let ad = &at.design;
    let f = |v: &[f64]| array(v, Precision::F64);
    let dims = dimension_consts(t, " Number of inputs (= error-signal components).");
    let Rules {
        statics,
        terms,
        rules,
    } = Rules::of(t);
    let Premises {
        map: premise_map,
        function: premise_fn,
        linear,
    } = Premises::of(t);
    let step_call = if linear {
        quote!(TABLE.step(&mut st, x, r))
    } else {
        quote!(TABLE.step_with_premises(&mut st, x, &premises(x), r))
    };
    let centres = matrix(&t.centres, Precision::F64);
    let (c, a_m, p_mat) = (f(&ad.c), f(&ad.a_m), f(&ad.p));
    let (a0, b0, d0) = (f(&ad.a0), f(&ad.b0), float(ad.d0, Precision::F64));
    let (rate_a, rate_b, rate_d) = (adaptation(&ad.a), adaptation(&ad.b), adaptation(&ad.d));
    let layer = float(ad.layer, Precision::F64);
    let dt = Literal::f64_unsuffixed(at.dt);
    let mut imports = vec![
        quote!(Adaptation),
        quote!(AdaptiveController),
        quote!(AdaptiveError),
        quote!(AdaptiveLaw),
        quote!(AdaptiveState),
        quote!(Flags),
    ];
    imports.extend(premise_imports(t));
    let state = state_type(t, step_call);
    let tokens = quote! {
        use tsf_runtime::{#(#imports),*};

        #dims
        /// The controller period in seconds: call `step` once every
        /// `SAMPLE_PERIOD` and hold its command in between; the update laws
        /// are integrated over this period (the spec's simulation step).
        pub const SAMPLE_PERIOD: f64 = #dt;

        #(#statics)*

        /// The error signal s = C x (M x N, row-major).
        #[allow(clippy::approx_constant, clippy::excessive_precision, clippy::unreadable_literal)]
        pub static ERROR_MAP: [f64; M * N] = #c;
        /// The reference model A_m (M x M, row-major).
        #[allow(clippy::approx_constant, clippy::excessive_precision, clippy::unreadable_literal)]
        pub static REFERENCE_MODEL: [f64; M * M] = #a_m;
        /// P with A_m' P + P A_m = -Q (M x M, row-major).
        #[allow(clippy::approx_constant, clippy::excessive_precision, clippy::unreadable_literal)]
        pub static LYAPUNOV: [f64; M * M] = #p_mat;

        /// Initial state-coefficient estimates a_ik (rule, then input, then state).
        #[allow(clippy::approx_constant, clippy::excessive_precision, clippy::unreadable_literal)]
        pub const A_HAT_0: [f64; R * M * N] = #a0;
        /// Initial input-gain estimates b_ik (rule, then input).
        #[allow(clippy::approx_constant, clippy::excessive_precision, clippy::unreadable_literal)]
        pub const B_HAT_0: [f64; R * M] = #b0;
        /// Initial disturbance-bound estimate d.
        #[allow(clippy::approx_constant, clippy::excessive_precision, clippy::unreadable_literal)]
        pub const D_HAT_0: f64 = #d0;

        /// The controller's tables (an adaptive design: no LMI certificate).
        #[allow(clippy::approx_constant, clippy::excessive_precision, clippy::unreadable_literal)]
        pub static TABLE: AdaptiveController<'static, N, M, P, R, D> = AdaptiveController {
            premise_map: #premise_map,
            terms: [#(#terms),*],
            rules: [#(#rules),*],
            centres: #centres,
            law: AdaptiveLaw {
                n: N,
                m: M,
                rules: R,
                c: &ERROR_MAP,
                a_m: &REFERENCE_MODEL,
                p: &LYAPUNOV,
                a: #rate_a,
                b: #rate_b,
                d: #rate_d,
                layer: #layer,
            },
            dt: SAMPLE_PERIOD,
        };

        #premise_fn

        #state
    };
    let body = unparse(tokens)?;
    Ok(format!("{}{body}", header(at)))
}

/// The caller-owned `State` of the adaptive law and its `step`
/// (`step_call`: the runtime call, with or without the premise function).
fn state_type(t: &Tables, step_call: TokenStream) -> TokenStream {
    let state_doc = format!("State order: {}.", t.state_names.join(", "));
    let input_doc = format!(
        "Input (and reference, error-signal) order: {}.",
        t.input_names.join(", ")
    );
    quote! {
        /// The adaptive controller's state, owned by the caller: the
        /// estimates, the reference model's state and what the last step did.
        #[doc = #state_doc]
        #[doc = #input_doc]
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct State {
            /// State-coefficient estimates a_ik (rule, then input, then state).
            pub a_hat: [f64; R * M * N],
            /// Input-gain estimates b_ik (rule, then input).
            pub b_hat: [f64; R * M],
            /// Disturbance-bound estimate d.
            pub d_hat: f64,
            /// Reference-model state s_m.
            pub s_m: [f64; M],
            flags: Flags,
            error: Option<AdaptiveError>,
            strengths: [f64; R],
        }

        impl State {
            /// The spec's initial estimates, s_m = 0, no step taken.
            pub const INIT: State = State {
                a_hat: A_HAT_0,
                b_hat: B_HAT_0,
                d_hat: D_HAT_0,
                s_m: [0.0; M],
                flags: Flags::NONE,
                error: None,
                strengths: [0.0; R],
            };

            /// The spec's initial state ([`State::INIT`]).
            pub const fn new() -> Self {
                Self::INIT
            }

            /// One control step at state `x` with reference `r` (the spec's
            /// r(t), evaluated by the caller; zeros to regulate): returns the
            /// command and advances the estimates and the reference model by
            /// `SAMPLE_PERIOD`. Never panics; a NaN or infinite state,
            /// premise, reference or command gives a zero command, leaves the
            /// estimates unchanged and sets [`State::error`].
            pub fn step(&mut self, x: &[f64; N], r: &[f64; M]) -> [f64; M] {
                let mut st = AdaptiveState {
                    a_hat: &mut self.a_hat,
                    b_hat: &mut self.b_hat,
                    d_hat: &mut self.d_hat,
                    s_m: &mut self.s_m,
                };
                let s = #step_call;
                self.flags = s.flags;
                self.error = s.error;
                self.strengths = s.h;
                s.u
            }

            /// Why the last step was refused (zero command, state held), if it was.
            pub fn error(&self) -> Option<AdaptiveError> {
                self.error
            }

            /// Whether the last step was refused.
            pub fn fault(&self) -> bool {
                self.error.is_some()
            }

            /// Flags of the last step's firing strengths.
            pub fn flags(&self) -> Flags {
                self.flags
            }

            /// Whether no rule fired in the last step (the nearest rule's strength 1).
            pub fn no_rule_fired(&self) -> bool {
                self.flags.contains(Flags::NO_RULE_FIRED)
            }

            /// Normalised firing strengths of the last step.
            pub fn strengths(&self) -> &[f64; R] {
                &self.strengths
            }
        }

        impl Default for State {
            fn default() -> Self {
                Self::new()
            }
        }
    }
}

/// The header comment (no timestamps, no absolute paths).
fn header(at: &AdaptiveTables) -> String {
    let t = &at.base;
    let mut s = generated_lines(&t.header);
    s.push_str(&format!(
        "// Precision f64: adaptive model-reference law, no LMI certificate (`tsfc compile` reports what\n// the Lyapunov argument guarantees and what it does not: docs/adaptive.md).\n//\n// Adaptive controller `{}`: {} states, {} inputs, {} rules, {} premise variables.\n// u_k = ((A_m (s - r))_k - sum_i h_i a_ik'x - d sat(p_k / phi)) / sum_i h_i b_ik with s = C x,\n// p = P (s - s_m); then the estimates and s_m advance by SAMPLE_PERIOD (explicit Euler, projection).\n\n",
        t.name, t.n, t.m, t.r, t.p
    ));
    s
}
