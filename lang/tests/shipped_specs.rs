//! Every shipped spec passes the checker: its premises can be generated and
//! it asks for no unsupported combination.

use std::path::Path;

#[test]
fn shipped_specs_are_accepted() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../specs");
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).expect("specs directory") {
        let path = entry.expect("entry").path();
        if path.extension().is_none_or(|e| e != "tsf") {
            continue;
        }
        let text = std::fs::read_to_string(&path).expect("readable");
        let (spec, diags) = tsf_lang::check_source(&text);
        let errors: Vec<_> = diags.iter().filter(|d| d.is_error()).collect();
        assert!(errors.is_empty(), "{}: {errors:#?}", path.display());
        assert!(spec.is_some(), "{}", path.display());
        count += 1;
    }
    assert!(count >= 3, "only {count} specs");
}
