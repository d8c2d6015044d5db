//! Embeds the shipped specs (`specs/*.tsf`) as the page's examples: writes
//! `$OUT_DIR/examples.rs`, a sorted list of `(file name, text)`.

use std::fmt::Write;
use std::path::Path;

fn main() {
    let specs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../specs");
    println!("cargo:rerun-if-changed={}", specs.display());
    let mut names: Vec<String> = std::fs::read_dir(&specs)
        .expect("the specs folder")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".tsf"))
        .collect();
    names.sort();
    let mut out = String::from("&[\n");
    for n in &names {
        let path = specs.join(n);
        println!("cargo:rerun-if-changed={}", path.display());
        let _ = writeln!(
            out,
            "    ({n:?}, include_str!({:?})),",
            path.display().to_string()
        );
    }
    out.push_str("]\n");
    let dest = Path::new(&std::env::var("OUT_DIR").expect("OUT_DIR")).join("examples.rs");
    std::fs::write(dest, out).expect("write examples.rs");
}
