//! The sensor-side trigger module `<controller>_sensor.rs` of an aperiodic
//! event trigger: constants, the weight and a `Sensor` wrapping the
//! runtime's trigger named by the law.

use super::tokens::{float, matrix, real_ty};
use super::unparse;
use crate::codegen::header::{law_summary, marker, sensor_certificate};
use crate::codegen::CodegenError;
use crate::tables::{SensorLaw, SensorTables, Tables};
use proc_macro2::{Literal, TokenStream};
use quote::quote;
use tsf_lang::spec::Precision;

/// The sensor-side trigger module `<controller>_sensor.rs`: decides at each
/// sampling instant whether to transmit the state, holds the last transmitted
/// state and the threshold. Errors if the design has no trigger.
pub fn emit_rust_sensor(t: &Tables) -> Result<String, CodegenError> {
    let s = t.sensor.aperiodic().ok_or(CodegenError::NoSensor)?;
    let prec = t.precision;
    let ty = real_ty(prec);
    let n = Literal::usize_unsuffixed(t.n);
    let (h_min, h_max) = (float(s.h_min, prec), float(s.h_max, prec));
    let (nu_min, nu_max) = (float(s.nu_min, prec), float(s.nu_max, prec));
    let weight = matrix(&s.weight, prec);
    let LawTokens {
        uses: law_use,
        items: law_items,
        field,
        init,
        nu_body,
        last_body,
        sample_body,
        doc: law_doc,
    } = law_tokens(s.law, prec);
    let docs = sensor_docs(t, s, law_doc);
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

/// The tokens of a sensor law: its `use`, its constants, the `Sensor`'s
/// field and initializer, the bodies of `nu`, `last` and `sample`, and the
/// law's doc paragraph.
struct LawTokens {
    uses: TokenStream,
    items: TokenStream,
    field: TokenStream,
    init: TokenStream,
    nu_body: TokenStream,
    last_body: TokenStream,
    sample_body: TokenStream,
    doc: &'static str,
}

/// The tokens of `law` in precision `prec`.
fn law_tokens(law: SensorLaw, prec: Precision) -> LawTokens {
    let ty = real_ty(prec);
    let (uses, items, field, init, nu_body, last_body, doc) = match law {
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
    let sample_body = match law {
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
    LawTokens {
        uses,
        items,
        field,
        init,
        nu_body,
        last_body,
        sample_body,
        doc,
    }
}

/// The doc paragraphs of `Sensor`, one per line with a leading space (as
/// `///` comments have), an empty line between two.
fn sensor_docs(t: &Tables, s: &SensorTables, law_doc: &str) -> Vec<String> {
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
    docs
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
