//! tsf-lmi
