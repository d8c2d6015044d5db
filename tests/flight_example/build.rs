//! Compiles the shipped Zhang & Zeng spec into `OUT_DIR/zhang_multiobjective.rs`.

fn main() -> Result<(), Box<dyn std::error::Error>> {
    tsfc::Builder::new()
        .spec("../../specs/zhang2013_multiobjective.tsf")
        .emit_rust(true)
        .compile()?;
    Ok(())
}
