//! Compiles the shipped specs (and the CSTR of `tests/specs/`) into `OUT_DIR/<controller>.rs` with tsfc's Builder.

fn main() -> Result<(), Box<dyn std::error::Error>> {
    tsfc::Builder::new()
        .spec("../../specs/zhang2013_multiobjective.tsf")
        .spec("../../specs/xu2020_event_triggered.tsf")
        .spec("../../specs/inverted_pendulum.tsf")
        .spec("../../specs/xue2024_markov_fault_tolerant.tsf")
        .spec("../../specs/wang2013_adaptive_mrac.tsf")
        .spec("../specs/cstr_exprel.tsf")
        .emit_rust(true)
        .compile()?;
    Ok(())
}
