//! tsf-lang
