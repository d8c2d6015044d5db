//! The observer-based controller in Rust (output feedback): the tables as a
//! `static` `tsf_runtime::Observer`, the caller-owned `State` (estimate,
//! strengths, flags), its initial value `INIT` and `step(&mut s, y) -> u`.

use super::tokens::{array, matrix, real_ty};
use super::{dimension_consts, gain_tokens, header, premise_imports, unparse, Premises, Rules};
use crate::codegen::CodegenError;
use crate::tables::{ObserverTables, Tables};
use proc_macro2::{Literal, TokenStream};
use quote::quote;

/// One matrix per rule as tokens.
fn per_rule(blocks: &[Vec<Vec<f64>>], t: &Tables) -> TokenStream {
    let items = blocks.iter().map(|b| matrix(b, t.precision));
    quote!([#(#items),*])
}

/// The header comment lines of the observer.
fn observer_header(o: &ObserverTables) -> String {
    let from = match o.output_map {
        Some(_) => "the measured output y",
        None => "the estimate xhat",
    };
    format!(
        "// Observer-based controller: {} measured outputs, period {} s; premises from {from}.\n// Call `step` once per `SAMPLE_PERIOD` with the sampled y and hold the command.\n",
        o.q, o.period
    )
}

/// The generated observer module's text (`t.observer` must be set).
pub fn emit_rust_observer(t: &Tables) -> Result<String, CodegenError> {
    let Some(o) = &t.observer else {
        return Err(CodegenError::ObserverUnsupported("no observer tables"));
    };
    crate::codegen::observer_supported(t)?;
    let prec = t.precision;
    let ty = real_ty(prec);
    let Rules {
        statics,
        terms: term_items,
        rules: rule_refs,
    } = Rules::of(t);
    let dims = dimension_consts(t, " Number of inputs.");
    let q = Literal::usize_unsuffixed(o.q);
    let period = Literal::f64_unsuffixed(o.period);
    let Premises {
        map: premise_map,
        function: premise_fn,
        linear,
    } = Premises::of(t);
    let step_call = if linear {
        quote!(TABLE.step(&mut s.xhat, y))
    } else {
        quote!(TABLE.step_with_premises(
            &mut s.xhat,
            y,
            &premises(&TABLE.premise_state(&s.xhat, y))
        ))
    };
    let output_map = match &o.output_map {
        Some(rows) => {
            let m = matrix(rows, prec);
            quote!(Some(#m))
        }
        None => quote!(None),
    };
    let centres = matrix(&t.centres, prec);
    let gains = gain_tokens(t);
    let u_max = array(&t.u_max, prec);
    let (phi, gu, gy) = (per_rule(&o.phi, t), per_rule(&o.gu, t), per_rule(&o.gy, t));
    let mut imports = vec![quote!(FactoredController), quote!(Flags), quote!(Observer)];
    imports.extend(premise_imports(t));
    let state_doc = format!("State order: {}.", t.state_names.join(", "));
    let input_doc = format!("Input order: {}.", t.input_names.join(", "));
    let tokens = quote! {
        use tsf_runtime::{#(#imports),*};

        #dims
        /// Number of measured outputs (y = C x).
        pub const Q: usize = #q;
        /// The controller's period in seconds: sample y and call `step` once every
        /// `SAMPLE_PERIOD`, holding the command in between (the observer is
        /// discretized exactly for this period).
        pub const SAMPLE_PERIOD: f64 = #period;

        #(#statics)*

        /// The controller's tables and every rule's discretized observer, certified by tsfc.
        #[allow(clippy::approx_constant, clippy::excessive_precision, clippy::unreadable_literal)]
        pub static TABLE: Observer<'static, #ty, N, M, Q, P, R, D> = Observer {
            controller: FactoredController {
                premise_map: #premise_map,
                terms: [#(#term_items),*],
                rules: [#(#rule_refs),*],
                centres: #centres,
                gains: #gains,
                u_max: #u_max,
            },
            output_map: #output_map,
            phi: #phi,
            gu: #gu,
            gy: #gy,
        };

        #premise_fn

        /// The controller's state, owned by the caller: the estimate of the state,
        /// the strengths and flags of the last step.
        #[doc = #state_doc]
        #[doc = #input_doc]
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct State {
            /// The state estimate xhat.
            pub xhat: [#ty; N],
            /// Normalised firing strengths of the last step.
            pub h: [#ty; R],
            /// Flags of the last step.
            pub flags: Flags,
        }

        /// The initial state: estimate 0, no step taken.
        pub const INIT: State = State { xhat: [0.0; N], h: [0.0; R], flags: Flags::NONE };

        /// One step: the saturated command for the measured output `y`; advances
        /// the estimate to the next sample. Never panics; a NaN or infinite `y`
        /// or estimate gives a zero command and a fault flag (a non-finite
        /// estimate is reset to 0, `Flags::ESTIMATE_RESET`).
        pub fn step(s: &mut State, y: &[#ty; Q]) -> [#ty; M] {
            let r = #step_call;
            s.h = r.h;
            s.flags = r.flags;
            r.u
        }
    };
    let body = unparse(tokens)?;
    let head = header(t);
    Ok(format!(
        "{}\n{}\n\n{body}",
        head.trim_end(),
        observer_header(o).trim_end()
    ))
}
