//! The certificate of the design as stored: every LMI re-checked with the
//! tables rounded as generated code stores them. A shipped spec certifies in
//! f64 and f32; a given-gain loop whose f32-rounded gain is unstable (checked
//! here by its eigenvalues, without LMIs) is refused in f32 naming the
//! failing LMI, and certified in f64.

use crate::common;

use common::{model_of, shipped, spec_path};
use nalgebra::DMatrix;
use tsf_lang::spec::Precision;
use tsfc::certify::StoredPrecision;
use tsfc::driver::compile::{compile, Compiled, Status};
use tsfc::report::SpecInfo;
use tsfc::synth::Settings;

/// x' = A x + B u: a strongly unstable second state (a22 = 999.3) the gain
/// cancels to within 1e-5, so that the closed loop is a lightly damped
/// oscillator (A + B F = [0, 1; -1, -1e-5]).
const A: [f64; 4] = [0.0, 1.0, 2.0, 999.3];
const B: [f64; 2] = [0.0, 1.0];
/// The given gain: trace(A + B F) = 999.3 - 999.30001 = -1e-5. Its second
/// entry is 1.2e-5 from the nearest f32 (999.29998779...), on the unstable
/// side: in f32 the trace is +1.2e-5.
const F: [f64; 2] = [-3.0, -999.30001];

fn spec(precision: &str) -> String {
    format!(
        "tsf 1; controller knife;\nstate x1, x2; input u;\n\
         A = [{:?}, {:?}; {:?}, {:?}]; B = [{:?}; {:?}];\n\
         premise x1 range -1 .. 1 {{ all = trap(-1, -1, 1, 1); }}\n\
         rule R: x1 is all => at(x1 = 0), F = [{:?}, {:?}];\n\
         objective stability;\nrelaxation basic;\nprecision {precision};\n",
        A[0], A[1], A[2], A[3], B[0], B[1], F[0], F[1]
    )
}

/// Largest real part of the eigenvalues of A + B f.
fn abscissa(f: [f64; 2]) -> f64 {
    let acl = DMatrix::from_row_slice(2, 2, &A)
        + DMatrix::from_column_slice(2, 1, &B) * DMatrix::from_row_slice(1, 2, &f);
    acl.complex_eigenvalues()
        .iter()
        .map(|l| l.re)
        .fold(f64::NEG_INFINITY, f64::max)
}

fn run(name: &str, text: &str) -> Compiled {
    let model = model_of(name, text);
    let info = SpecInfo {
        path: name.into(),
        sha256: String::new(),
    };
    compile(&model, info, &Settings::default(), Default::default())
}

fn stored(c: &Compiled) -> &StoredPrecision {
    c.report
        .stored_precision
        .as_ref()
        .unwrap_or_else(|| panic!("no stored-precision check: {:?}", c.report.diagnosis))
}

#[test]
fn a_shipped_spec_certifies_in_stored_precision_f64_and_f32() {
    let text = std::fs::read_to_string(spec_path("inverted_pendulum.tsf")).expect("spec");
    assert_eq!(
        shipped("inverted_pendulum.tsf").spec.precision,
        Precision::F64
    );
    for precision in ["f64", "f32"] {
        let text = text.replace("precision f64;", &format!("precision {precision};"));
        let c = run("inverted_pendulum.tsf", &text);
        assert_eq!(c.status, Status::Certified, "{precision}");
        let s = stored(&c);
        assert_eq!(s.precision, precision);
        assert!(s.certified, "{precision}: {s:?}");
        assert_eq!(c.report.stored_precision_certified, Some(true));
        assert!(s.worst_margin > 0.0 && s.worst_margin.is_finite());
        let cert = c.report.certificate.as_ref().expect("certificate");
        assert_eq!(s.conditions, cert.lmis.len(), "every LMI re-checked");
        // The gains move by at most one rounding: the margin barely moves.
        let rel = (s.worst_margin - cert.min_margin).abs() / cert.min_margin;
        assert!(
            rel < 1e-3,
            "{precision}: {} vs {}",
            s.worst_margin,
            cert.min_margin
        );
        let m = &s.membership_rounding_bound;
        assert!(m.holds && m.required_margin > 0.0 && m.required_margin < m.available_margin);
        if precision == "f64" {
            assert_eq!(
                s.max_relative_rounding, 0.0,
                "f64 stores every gain exactly"
            );
        } else {
            let u = f64::from(f32::EPSILON) / 2.0;
            assert!(s.max_relative_rounding > 0.0 && s.max_relative_rounding <= u);
        }
    }
}

#[test]
fn the_constructed_loop_is_stable_in_f64_and_unstable_in_f32() {
    let f32_gain = F.map(|v| f64::from(v as f32));
    assert_ne!(f32_gain, F, "rounding moves the gain");
    let (exact, rounded) = (abscissa(F), abscissa(f32_gain));
    assert!(
        exact < 0.0 && exact > -1e-5,
        "exact gain: max Re eig = {exact:e}"
    );
    assert!(rounded > 0.0, "f32 gain: max Re eig = {rounded:e}");
}

#[test]
fn f32_rounding_that_breaks_the_certificate_is_refused_naming_the_lmi() {
    let c = run("knife.tsf", &spec("f32"));
    assert_eq!(c.status, Status::Refused);
    assert_eq!(c.report.stored_precision_certified, Some(false));
    assert!(c.report.gains.is_empty(), "no gains emitted");
    let s = stored(&c);
    assert_eq!(s.precision, "f32");
    assert!(!s.certified);
    assert!(s.worst_margin < 0.0, "{s:?}");
    // The failing LMI is one of the certificate's, and the diagnosis names it.
    let cert = c.report.certificate.as_ref().expect("certificate");
    assert!(
        cert.lmis.iter().any(|l| l.name == s.worst_lmi) && s.worst_lmi != "X > 0",
        "{s:?}"
    );
    let diag = c.report.diagnosis.as_ref().expect("diagnosis");
    assert!(
        diag.message.contains("stored precision f32")
            && diag.message.contains(&format!("`{}`", s.worst_lmi)),
        "{}",
        diag.message
    );
}

#[test]
fn the_same_loop_in_f64_is_certified() {
    let c = run("knife.tsf", &spec("f64"));
    assert_eq!(c.status, Status::Certified, "{:?}", c.report.diagnosis);
    let s = stored(&c);
    assert_eq!(s.precision, "f64");
    assert!(s.certified && s.worst_margin > 0.0, "{s:?}");
    assert_eq!(s.max_relative_rounding, 0.0);
    let cert = c.report.certificate.as_ref().expect("certificate");
    assert_eq!(
        s.worst_margin, cert.min_margin,
        "given gains: the same LMIs"
    );
}

#[test]
fn the_cli_pipeline_refuses_with_exit_code_3() {
    let dir = std::env::temp_dir().join(format!("tsfc-stored-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("knife.tsf");
    std::fs::write(&path, spec("f32")).expect("write");
    let run = tsfc::pipeline::read(&path)
        .and_then(|f| f.compile(&Settings::default()))
        .expect("compiles");
    assert_eq!(run.exit_code(), 3);
    let e = run.certified().expect_err("refused");
    assert!(e.message.contains("stored precision f32"), "{}", e.message);
    let _ = std::fs::remove_dir_all(&dir);
}
