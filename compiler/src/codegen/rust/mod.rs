//! The Rust generator: a `no_std` module built with proc-macro2 + quote and
//! formatted with prettyplease. It declares the tables as `static` data for
//! `tsf_runtime::Controller` and wraps them in a small `Controller` struct.
//! The generated file is meant to be `include!`d (no inner attributes).
//!
//! `tokens` builds literals, arrays and premise expressions; `sensor`
//! the sensor-side module of an aperiodic event trigger.

mod adaptive;
mod observer;
mod sensor;
mod signal_sensor;
mod tokens;

pub use adaptive::emit_rust_adaptive;
pub use observer::emit_rust_observer;
pub use sensor::emit_rust_sensor;
pub use signal_sensor::emit_rust_signal_sensor;

use super::header::{marker, modal_sampling_note, sensor_name};
use super::{Backend, CodegenError, GeneratedFile};
use crate::model::TermSpec;
use crate::tables::{AdaptiveTables, PremiseCode, Sensor, Tables};
use proc_macro2::{Literal, TokenStream};
use quote::{format_ident, quote};
use tokens::{array, float, matrix, membership, real_ty, sym};
use tsf_lang::spec::Emit;

/// The Rust backend: `<name>.rs`, and `<name>_sensor.rs` for an aperiodic
/// event trigger.
#[derive(Debug, Clone, Copy)]
pub struct RustBackend;

impl Backend for RustBackend {
    fn target(&self) -> Emit {
        Emit::Rust
    }

    fn controller(&self, t: &Tables) -> Result<Vec<GeneratedFile>, CodegenError> {
        let text = match t.observer {
            Some(_) => emit_rust_observer(t)?,
            None => emit_rust(t)?,
        };
        Ok(vec![GeneratedFile {
            name: format!("{}.rs", t.name),
            text,
        }])
    }

    fn sensor(&self, t: &Tables) -> Result<Vec<GeneratedFile>, CodegenError> {
        let text = match &t.sensor {
            Sensor::None => return Ok(Vec::new()),
            Sensor::Aperiodic(_) => emit_rust_sensor(t)?,
            Sensor::Mixed(_) => emit_rust_signal_sensor(t)?,
        };
        Ok(vec![GeneratedFile {
            name: format!("{}.rs", sensor_name(t)),
            text,
        }])
    }

    fn adaptive(&self, at: &AdaptiveTables) -> Result<Vec<GeneratedFile>, CodegenError> {
        Ok(vec![GeneratedFile {
            name: format!("{}.rs", at.base.name),
            text: emit_rust_adaptive(at)?,
        }])
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

/// The generated module's text.
pub fn emit_rust(t: &Tables) -> Result<String, CodegenError> {
    let prec = t.precision;
    let ty = real_ty(prec);
    let Rules {
        statics,
        terms: term_items,
        rules: rule_refs,
    } = Rules::of(t);
    let dims = dimension_consts(t, " Number of inputs.");
    let modal = Modal::of(t);
    let mode_arg = modal.as_ref().map(|_| quote!(mode,));
    let Premises {
        map: premise_map,
        function: premise_fn,
        linear,
    } = Premises::of(t);
    let step_body = if linear {
        quote!(TABLE.step(#mode_arg x))
    } else {
        quote!(TABLE.step_with_premises(#mode_arg x, &premises(x)))
    };
    let centres = matrix(&t.centres, prec);
    let gains = gain_tokens(t);
    let u_max = array(&t.u_max, prec);
    let state_doc = format!("State order: {}.", t.state_names.join(", "));
    let input_doc = format!("Input order: {}.", t.input_names.join(", "));
    let mut imports = vec![
        modal
            .as_ref()
            .map_or(quote!(FactoredController), |_| quote!(ModalController)),
        quote!(Flags),
    ];
    imports.extend(premise_imports(t));
    let sampling_note = modal_sampling_note(t).map(|n| format!(" {n}"));
    let sampling = sampling_consts(t.header.sampling, sampling_note.as_deref());
    let StepTokens {
        table_ty,
        table_ctor,
        mode_consts,
        step_sig,
        step_doc,
        mode_accessor,
    } = step_tokens(t, modal.as_ref());
    let tokens = quote! {
        use tsf_runtime::{#(#imports),*};

        #dims
        #mode_consts
        #sampling

        #(#statics)*

        /// The controller's tables, certified by tsfc.
        #[allow(clippy::approx_constant, clippy::excessive_precision, clippy::unreadable_literal)]
        pub static TABLE: #table_ty = #table_ctor {
            premise_map: #premise_map,
            terms: [#(#term_items),*],
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

            #step_doc
            #step_sig {
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

            #mode_accessor
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

/// The gains as tokens: one matrix per rule, one such set per mode with modes.
fn gain_tokens(t: &Tables) -> TokenStream {
    let prec = t.precision;
    let gain_set = |set: &[Vec<Vec<f64>>]| {
        let items = set.iter().map(|g| matrix(g, prec));
        quote!([#(#items),*])
    };
    let gains = match &t.modes {
        Some(mt) => {
            let sets = mt.gains.iter().map(|set| gain_set(set));
            quote!([#(#sets),*])
        }
        None => gain_set(&t.gains),
    };
    gains
}

/// What the controller's step depends on modes for: the table's type and
/// constructor, the mode constants, `step`'s signature and doc, and the
/// mode accessor.
struct StepTokens {
    table_ty: TokenStream,
    table_ctor: TokenStream,
    mode_consts: TokenStream,
    step_sig: TokenStream,
    step_doc: TokenStream,
    mode_accessor: TokenStream,
}

/// The [`StepTokens`] of `t`, with `modal` its mode constants if it has modes.
fn step_tokens(t: &Tables, modal: Option<&Modal>) -> StepTokens {
    let ty = real_ty(t.precision);
    match modal {
        Some(md) => StepTokens {
            table_ty: quote!(ModalController<'static, #ty, N, M, P, R, D, K>),
            table_ctor: quote!(ModalController),
            mode_consts: md.consts.clone(),
            step_sig: quote!(pub fn step(&mut self, mode: u8, x: &[#ty; N]) -> [#ty; M]),
            step_doc: {
                let note = modal_sampling_note(t).map(|n| {
                    let n = format!(" {n}");
                    quote!(#[doc = ""] #[doc = #n])
                });
                quote! {
                    /// One control update in mode `mode` (an index of `MODE_NAMES`, from
                    /// fault detection): the saturated command for state `x` with that
                    /// mode's gains. Never panics; NaN or infinite states give a zero
                    /// command and a fault flag; a mode `>= K` uses mode 0's gains and
                    /// raises `Flags::MODE_OUT_OF_RANGE`.
                    #note
                }
            },
            mode_accessor: quote! {
                /// Whether the last step was given a mode `>= K` (mode 0's gains used).
                pub fn mode_out_of_range(&self) -> bool {
                    self.flags.contains(Flags::MODE_OUT_OF_RANGE)
                }
            },
        },
        None => StepTokens {
            table_ty: quote!(FactoredController<'static, #ty, N, M, P, R, D>),
            table_ctor: quote!(FactoredController),
            mode_consts: quote!(),
            step_sig: quote!(pub fn step(&mut self, x: &[#ty; N]) -> [#ty; M]),
            step_doc: quote! {
                /// One control update: the saturated command for state `x`.
                /// Never panics; NaN or infinite states give a zero command and a fault flag.
            },
            mode_accessor: quote!(),
        },
    }
}

/// The rule premises as tokens: the statics (`about` points, one index array
/// per rule), the distinct terms' initializers (`Term::Is { .. }`, ...) and
/// the rules' references to their index arrays.
struct Rules {
    statics: Vec<TokenStream>,
    terms: Vec<TokenStream>,
    rules: Vec<TokenStream>,
}

impl Rules {
    /// The distinct terms (each evaluated once per step) and one static
    /// index array per rule.
    fn of(t: &Tables) -> Self {
        let prec = t.precision;
        let ty = real_ty(prec);
        let mut statics = Vec::new();
        let mut term_items = Vec::new();
        for (k, term) in t.factored.terms.iter().enumerate() {
            match term {
                TermSpec::Is { var, set } => {
                    let var = Literal::usize_unsuffixed(*var);
                    let set = membership(set, prec);
                    term_items.push(quote!(Term::Is { var: #var, set: #set }));
                }
                TermSpec::About {
                    first,
                    point,
                    sigma,
                } => {
                    let pt = format_ident!("POINT_{}", k + 1);
                    let len = Literal::usize_unsuffixed(point.len());
                    let vals = array(point, prec);
                    let doc = format!(" Operating point of `about` term {k} of `TABLE.terms`.");
                    statics.push(quote! {
                        #[doc = #doc]
                        #[allow(clippy::approx_constant, clippy::excessive_precision)]
                        static #pt: [#ty; #len] = #vals;
                    });
                    let first = Literal::usize_unsuffixed(*first);
                    let sigma = float(*sigma, prec);
                    term_items
                        .push(quote!(Term::About { first: #first, point: &#pt, sigma: #sigma }));
                }
            }
        }
        let mut rule_refs = Vec::new();
        for (ri, indices) in t.factored.rules.iter().enumerate() {
            let ident = format_ident!("RULE_{}", ri + 1);
            let count = Literal::usize_unsuffixed(indices.len());
            let items = indices.iter().map(|k| Literal::usize_unsuffixed(*k));
            let doc = format!(
                " Premise of rule {}: indices into `TABLE.terms`, multiplied in order.",
                t.rule_names.get(ri).map_or("?", String::as_str)
            );
            statics.push(quote! {
                #[doc = #doc]
                static #ident: [usize; #count] = [#(#items),*];
            });
            rule_refs.push(quote!(&#ident));
        }
        Rules {
            statics,
            terms: term_items,
            rules: rule_refs,
        }
    }
}

/// The premise code as tokens: the table's `premise_map` (zeros when the
/// premises are expressions) and, for expressions, `fn premises(x)`.
struct Premises {
    map: TokenStream,
    function: TokenStream,
    /// Whether `z = L x` (the table's own step computes the premises).
    linear: bool,
}

impl Premises {
    fn of(t: &Tables) -> Self {
        let prec = t.precision;
        let ty = real_ty(prec);
        match &t.premise {
            PremiseCode::Linear(l) => Premises {
                map: matrix(l, prec),
                function: quote!(),
                linear: true,
            },
            PremiseCode::Exprs(exprs) => {
                let zero_rows: Vec<Vec<f64>> = (0..t.p).map(|_| vec![0.0; t.n]).collect();
                let items = exprs.iter().map(|e| sym(e, prec));
                Premises {
                    map: matrix(&zero_rows, prec),
                    function: quote! {
                        /// The premise variables z as functions of the state (from the spec).
                        #[allow(clippy::approx_constant, clippy::excessive_precision)]
                        pub fn premises(x: &[#ty; N]) -> [#ty; P] {
                            [#(#items),*]
                        }
                    },
                    linear: false,
                }
            }
        }
    }
}

/// The dimension constants `N, M, P, R, D` of a generated module; `m_doc` is
/// `M`'s doc line (with its leading space, as `///` writes it).
fn dimension_consts(t: &Tables, m_doc: &str) -> TokenStream {
    let lit = Literal::usize_unsuffixed;
    let (n, m, p) = (lit(t.n), lit(t.m), lit(t.p));
    let (r, d) = (lit(t.r), lit(t.factored.terms.len()));
    quote! {
        /// Number of states.
        pub const N: usize = #n;
        #[doc = #m_doc]
        pub const M: usize = #m;
        /// Number of premise variables.
        pub const P: usize = #p;
        /// Number of rules.
        pub const R: usize = #r;
        /// Number of distinct premise terms (each evaluated once per step).
        pub const D: usize = #d;
    }
}

/// The runtime items the premise code and rule terms use.
fn premise_imports(t: &Tables) -> Vec<TokenStream> {
    let mut imports = Vec::new();
    if t.factored
        .terms
        .iter()
        .any(|x| matches!(x, TermSpec::Is { .. }))
    {
        imports.push(quote!(Membership));
    }
    if matches!(t.premise, PremiseCode::Exprs(_)) {
        imports.push(quote!(Real));
    }
    if !t.factored.terms.is_empty() {
        imports.push(quote!(Term));
    }
    imports
}

/// The mode constants of a mode-dependent design (`K`, `MODE_NAMES`).
struct Modal {
    consts: TokenStream,
}

impl Modal {
    /// `Some` when the tables carry per-mode gains.
    fn of(t: &Tables) -> Option<Self> {
        let mt = t.modes.as_ref()?;
        let k = Literal::usize_unsuffixed(mt.names.len());
        let names = mt.names.iter().map(|n| Literal::string(n));
        Some(Modal {
            consts: quote! {
                /// Number of Markov-switching modes (gain sets).
                pub const K: usize = #k;
                /// Mode names: `step`'s `mode` argument indexes this list.
                pub const MODE_NAMES: [&str; K] = [#(#names),*];
            },
        })
    }
}

/// The header comment (no timestamps, no absolute paths).
fn header(t: &Tables) -> String {
    let h = &t.header;
    let mut s = marker(h);
    s.push_str(&format!(
        "// Controller `{}`: {} states, {} inputs, {} rules, {} premise variables; relaxation {}.\n",
        t.name, t.n, t.m, t.r, t.p, h.relaxation
    ));
    if let Some(mt) = &t.modes {
        s.push_str(&format!(
            "// Mode-dependent gains: {} modes ({}); `step` takes the active mode (from fault detection).\n",
            mt.names.len(),
            mt.names.join(", ")
        ));
        if let Some(note) = modal_sampling_note(t) {
            s.push_str(&format!("// {note}\n"));
        }
    }
    if t.sensor.aperiodic().is_some() {
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

/// The certified sampling as constants: `SAMPLE_PERIOD` for a periodic
/// trigger, `SAMPLE_INTERVAL_MIN` / `_MAX` for aperiodic sampling.
/// With modes, `modal` is the doc line (with its leading space) of what the
/// caller must do at mode changes.
fn sampling_consts(sampling: Option<(f64, f64)>, modal: Option<&str>) -> TokenStream {
    match (sampling, modal) {
        (None, _) => TokenStream::new(),
        (Some((lo, hi)), Some(note)) if lo == hi => {
            let h = Literal::f64_unsuffixed(hi);
            quote! {
                /// The certified sampling period in seconds: sample the state and call
                /// `step` once every `SAMPLE_PERIOD`.
                #[doc = #note]
                pub const SAMPLE_PERIOD: f64 = #h;
            }
        }
        (Some((lo, hi)), Some(note)) => {
            let (lo, hi) = (Literal::f64_unsuffixed(lo), Literal::f64_unsuffixed(hi));
            quote! {
                /// Shortest interval in seconds between two samples of the state.
                pub const SAMPLE_INTERVAL_MIN: f64 = #lo;
                /// Longest certified interval in seconds between two samples of the state.
                #[doc = #note]
                pub const SAMPLE_INTERVAL_MAX: f64 = #hi;
            }
        }
        (Some((lo, hi)), None) if lo == hi => {
            let h = Literal::f64_unsuffixed(hi);
            quote! {
                /// The certified sampling period in seconds: call `step` once every
                /// `SAMPLE_PERIOD` and hold its command in between (zero-order hold).
                /// The certificate covers this period only.
                pub const SAMPLE_PERIOD: f64 = #h;
            }
        }
        (Some((lo, hi)), None) => {
            let (lo, hi) = (Literal::f64_unsuffixed(lo), Literal::f64_unsuffixed(hi));
            quote! {
                /// Shortest certified interval in seconds between two calls of `step`
                /// (the command is held in between).
                pub const SAMPLE_INTERVAL_MIN: f64 = #lo;
                /// Longest certified interval in seconds between two calls of `step`.
                pub const SAMPLE_INTERVAL_MAX: f64 = #hi;
            }
        }
    }
}
