//! The end-to-end suite: one test binary (one link, one set of debug-free
//! artifacts) whose modules are the former per-file test crates.

mod adaptive;
mod adaptive_codegen;
mod amrr;
mod c_codegen;
mod common;
mod compat;
mod diagnostics;
mod event_trigger;
mod fuzz;
mod fuzz_pipeline;
mod fuzzy_lyapunov;
mod given_gains;
mod markov;
mod markov_performance;
mod markov_runtime;
mod markov_sampled;
mod mismatch_kappa;
mod mixed_trigger;
mod model_consistency;
mod monte_carlo;
mod objectives;
mod plots;
mod region;
mod relaxation_map;
mod rust_codegen;
mod sampled_loop;
mod sector;
mod shipped_specs;
mod sim_evaluators;
mod simulation;
mod solver_scaling;
mod stored_precision;
mod sweep;
mod synthesis;
mod xu_paper_evidence;
