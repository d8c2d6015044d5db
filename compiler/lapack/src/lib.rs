//! tsf-lapack
