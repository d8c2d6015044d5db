//! Pure-Rust BLAS/LAPACK symbols for Clarabel's SDP path, backed by faer.
//!
//! Clarabel built with `features = ["sdp", "blas-src", "lapack-src"]` and no
//! provider leaves the Fortran-ABI symbols below undefined at link time. This
//! crate defines them (`#[no_mangle] extern "C"`, double precision only) with
//! the argument lists of `blas-sys` 0.7 / `lapack-sys` 0.14, so the build
//! needs nothing but crates.io:
//!
//! * BLAS: [`dgemm_`], [`dgemv_`], [`dsymv_`], [`dsyrk_`], [`dsyr2k_`];
//! * LAPACK: [`dpotrf_`], [`dpotrs_`], [`dsyevr_`], [`dgesdd_`], [`dgesvd_`].
//!
//! # Linking
//! A library crate nothing refers to is not linked, and its symbols are then
//! missing. Every final artefact (binary, test, example) that links Clarabel
//! must refer to this crate, e.g.
//!
//! ```
//! use tsf_lapack as _;
//! // or, explicitly:
//! tsf_lapack::link();
//! ```
//!
//! # Conventions
//! Column-major storage with leading dimensions, character options are
//! case-insensitive, no hidden string-length arguments. Illegal arguments
//! give `info = -position` (LAPACK) or a message on stderr and an untouched
//! output (BLAS). Details per routine are in their docs.

mod blas;
mod ffi;
mod lapack;

pub use blas::{dgemm_, dgemv_, dsymv_, dsyr2k_, dsyrk_};
pub use lapack::{dgesdd_, dgesvd_, dpotrf_, dpotrs_, dsyevr_};

/// Does nothing; calling it (or `use tsf_lapack as _;`) makes sure this crate,
/// and with it the BLAS/LAPACK symbols, is linked into the final artefact.
#[inline(never)]
pub fn link() {}
