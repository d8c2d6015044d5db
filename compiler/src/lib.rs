//! tsfc
