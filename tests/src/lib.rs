//! End-to-end test crate for tsfc; the tests live in `tests/tests/`.
