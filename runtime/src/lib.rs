#![no_std]
//! tsf-runtime
