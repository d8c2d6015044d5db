//! tsfc in the browser: the functions the playground page's worker
//! (`playground/web/worker.js`) calls, each taking one spec text and returning
//! a JSON document. They call the library functions the `tsfc` binary calls,
//! so diagnostics, reports and generated code are the command line's; see
//! `docs/playground.md`.
//!
//! The module is built for `wasm32-wasip1` and exported as plain C functions:
//! strings cross as UTF-8 bytes in the module's memory ([`tsfc_alloc`] gives
//! the page a buffer to fill; each call takes its arguments' buffers and
//! leaves its answer for [`tsfc_result_ptr`] / [`tsfc_result_len`]).

pub mod certify;
pub mod check;
pub mod examples;
pub mod limits;
pub mod simulate;

use std::cell::RefCell;

thread_local! {
    /// The answer of the last call, until the next one.
    static RESULT: RefCell<Vec<u8>> = const { RefCell::new(Vec::new()) };
}

/// A buffer of `len` bytes for the page to write an argument into; the call
/// it is passed to takes it back.
#[no_mangle]
pub extern "C" fn tsfc_alloc(len: usize) -> *mut u8 {
    Box::into_raw(vec![0u8; len].into_boxed_slice()).cast()
}

/// Takes back a buffer of [`tsfc_alloc`] as text (invalid UTF-8 replaced).
///
/// # Safety
/// `ptr` and `len` come from one [`tsfc_alloc`] call, not yet taken back.
unsafe fn take(ptr: *mut u8, len: usize) -> String {
    // SAFETY: by the contract above, this is the boxed slice tsfc_alloc leaked.
    let bytes = unsafe { Box::from_raw(std::ptr::slice_from_raw_parts_mut(ptr, len)) };
    String::from_utf8_lossy(&bytes).into_owned()
}

/// Stores `answer` as the last result and returns its length in bytes.
fn answer(answer: serde_json::Value) -> usize {
    let bytes = answer.to_string().into_bytes();
    let len = bytes.len();
    RESULT.with(|r| *r.borrow_mut() = bytes);
    len
}

/// Where the last answer's bytes are (valid until the next call).
#[no_mangle]
pub extern "C" fn tsfc_result_ptr() -> *const u8 {
    RESULT.with(|r| r.borrow().as_ptr())
}

/// The last answer's length in bytes.
#[no_mangle]
pub extern "C" fn tsfc_result_len() -> usize {
    RESULT.with(|r| r.borrow().len())
}

/// The diagnostics of the spec `text` named `name` ([`check::check`]).
///
/// # Safety
/// Each pointer and length pair comes from one [`tsfc_alloc`] call.
#[no_mangle]
pub unsafe extern "C" fn tsfc_check(
    name: *mut u8,
    name_len: usize,
    text: *mut u8,
    text_len: usize,
) -> usize {
    // SAFETY: forwarded contract.
    let (name, text) = unsafe { (take(name, name_len), take(text, text_len)) };
    answer(check::check(&name, &text))
}

/// Synthesis, certificate, report and generated Rust and C of the spec
/// ([`certify::certify`]).
///
/// # Safety
/// Each pointer and length pair comes from one [`tsfc_alloc`] call.
#[no_mangle]
pub unsafe extern "C" fn tsfc_certify(
    name: *mut u8,
    name_len: usize,
    text: *mut u8,
    text_len: usize,
) -> usize {
    // SAFETY: forwarded contract.
    let (name, text) = unsafe { (take(name, name_len), take(text, text_len)) };
    answer(certify::certify(&name, &text))
}

/// The closed-loop simulation of the spec ([`simulate::simulate`]) over
/// `horizon` seconds (zero, negative or NaN: the spec's span).
///
/// # Safety
/// Each pointer and length pair comes from one [`tsfc_alloc`] call.
#[no_mangle]
pub unsafe extern "C" fn tsfc_simulate(
    name: *mut u8,
    name_len: usize,
    text: *mut u8,
    text_len: usize,
    horizon: f64,
) -> usize {
    // SAFETY: forwarded contract.
    let (name, text) = unsafe { (take(name, name_len), take(text, text_len)) };
    let horizon = (horizon.is_finite() && horizon > 0.0).then_some(horizon);
    answer(simulate::simulate(&name, &text, horizon))
}

/// The examples (the shipped specs) and the limits, for the page's menu and notes.
#[no_mangle]
pub extern "C" fn tsfc_about() -> usize {
    answer(serde_json::json!({
        "version": env!("CARGO_PKG_VERSION"),
        "examples": examples::EXAMPLES
            .iter()
            .map(|(name, text)| serde_json::json!({ "name": name, "text": text }))
            .collect::<Vec<_>>(),
        "limits": {
            "spec_bytes": limits::MAX_SPEC_BYTES,
            "states": limits::MAX_STATES,
            "rules": limits::MAX_RULES,
            "sim_steps": limits::MAX_SIM_STEPS,
        },
    }))
}

/// The plots' font: DejaVu Sans, the bytes the native plots embed. The page
/// registers it (`FontFace`) for the inline SVG plots, so their text is drawn
/// with the font shipped inside tsfc, never a system font.
#[no_mangle]
pub extern "C" fn tsfc_font() -> usize {
    let bytes = dejavu::sans::regular().to_vec();
    let len = bytes.len();
    RESULT.with(|r| *r.borrow_mut() = bytes);
    len
}

#[cfg(test)]
mod tests {
    /// A string passed through the exported buffer calls comes back as the
    /// answer the module function gives.
    #[test]
    fn strings_cross_the_boundary() {
        let pass = |s: &str| {
            let p = super::tsfc_alloc(s.len());
            // SAFETY: p has s.len() bytes.
            unsafe { std::ptr::copy_nonoverlapping(s.as_ptr(), p, s.len()) };
            p
        };
        let text = "tsf 1;\ncontroller c;\nstate x;\nbogus;\n";
        let len = unsafe { super::tsfc_check(pass("a.tsf"), 5, pass(text), text.len()) };
        assert_eq!(len, super::tsfc_result_len());
        let got = unsafe { std::slice::from_raw_parts(super::tsfc_result_ptr(), len) };
        let v: serde_json::Value = serde_json::from_slice(got).expect("JSON");
        assert_eq!(v, super::check::check("a.tsf", text));
        assert_eq!(v["ok"], false);
    }
}
