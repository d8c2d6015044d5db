//! The sensor-side module `<controller>_sensor.rs` of a mixed trigger on a
//! named signal: the signal's evaluation from the state, BETA, RHO and a
//! `Sensor` wrapping the runtime's `SignalTrigger` (it transmits and holds the
//! state x(t_i); the controller computes u = PDC(x(t_i))).

use super::tokens::{float, real_ty, sym};
use super::unparse;
use crate::codegen::header::marker;
use crate::codegen::CodegenError;
use crate::tables::{SignalSensorTables, Tables};
use proc_macro2::Literal;
use quote::quote;

/// The sensor module of a mixed trigger on a signal; errors if the design has none.
pub fn emit_rust_signal_sensor(t: &Tables) -> Result<String, CodegenError> {
    let s = t.sensor.mixed().ok_or(CodegenError::NoSensor)?;
    let prec = t.precision;
    let ty = real_ty(prec);
    let n = Literal::usize_unsuffixed(t.n);
    let k = Literal::usize_unsuffixed(s.exprs.len());
    let (beta, rho) = (float(s.beta, prec), float(s.rho, prec));
    let items = s.exprs.iter().map(|e| sym(e, prec));
    let mut funcs = Vec::new();
    for e in &s.exprs {
        e.functions(&mut funcs);
    }
    let real = if funcs.is_empty() {
        quote!()
    } else {
        quote!(Real,)
    };
    let signal_doc = format!(
        " The monitored signal `{}` as a function of the state (from the spec).",
        s.signal
    );
    let sensor_doc = [
        format!(
            " Sensor-side mixed trigger (Amrr et al. 2019) on `{}`: transmit the state x when \
             ||s(x(t_i)) - s(x)|| >= BETA ||s(x)|| + RHO (tsf_runtime::SignalTrigger; NaN transmits).",
            s.signal
        ),
        String::new(),
        format!(
            " Call [`Sensor::sample`] {}; feed every transmitted state to the controller module `{}` \
             (`Controller::step`), which holds its command until the next transmission.",
            if s.monitor == "step" {
                "at every control step (`monitor = step`)"
            } else {
                "as often as the platform allows (`monitor = continuous`: the certificate assumes continuous monitoring)"
            },
            t.name
        ),
        String::new(),
        format!(" State order: {}.", t.state_names.join(", ")),
    ];
    let tokens = quote! {
        use tsf_runtime::{#real SignalTrigger};

        /// Number of states.
        pub const N: usize = #n;
        /// Number of components of the monitored signal.
        pub const K: usize = #k;
        /// Relative coefficient beta of the law.
        #[allow(clippy::approx_constant, clippy::excessive_precision)]
        pub const BETA: #ty = #beta;
        /// Absolute offset rho of the law.
        #[allow(clippy::approx_constant, clippy::excessive_precision)]
        pub const RHO: #ty = #rho;

        #[doc = #signal_doc]
        #[allow(clippy::approx_constant, clippy::excessive_precision)]
        pub fn signal(x: &[#ty; N]) -> [#ty; K] {
            [#(#items),*]
        }

        #(#[doc = #sensor_doc])*
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct Sensor {
            trigger: SignalTrigger<#ty, N, K>,
        }

        impl Sensor {
            /// Number of states.
            pub const N: usize = N;

            /// A sensor that has transmitted nothing yet (the first sample transmits).
            pub const fn new() -> Self {
                Sensor { trigger: SignalTrigger::new(BETA, RHO) }
            }

            /// Decides on the current state: `Some(x)` if `x` is transmitted now
            /// (it becomes x(t_i)), `None` otherwise. Never panics.
            pub fn sample(&mut self, x: &[#ty; N]) -> Option<[#ty; N]> {
                let s = signal(x);
                self.trigger.decide(x, &s)
            }

            /// Last transmitted state x(t_i), if any.
            pub fn last(&self) -> Option<&[#ty; N]> {
                self.trigger.last()
            }
        }

        impl Default for Sensor {
            fn default() -> Self {
                Self::new()
            }
        }
    };
    let body = unparse(tokens)?;
    Ok(format!("{}{body}", header(t, s)))
}

/// Header comment of the module.
fn header(t: &Tables, s: &SignalSensorTables) -> String {
    let mut out = marker(&t.header);
    out.push_str(&format!(
        "// Sensor-side mixed trigger of controller `{}` ({} states) on the signal `{}` ({} components,\n\
         // monitor = {}): transmits x when ||s(x(t_i)) - s(x)|| >= {:?} ||s(x)|| + {:?}; the controller\n\
         // module `{}` is fed the transmitted x(t_i).\n// certificate: {}.\n\n",
        t.name,
        t.n,
        s.signal,
        s.exprs.len(),
        s.monitor,
        s.beta,
        s.rho,
        t.name,
        s.certificate
    ));
    out
}
