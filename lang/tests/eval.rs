//! Expression evaluation: precedence, matrices, built-ins, errors.

use tsf_lang::check_source;

/// A valid spec to which the expression is appended as a constant.
const SPEC: &str = "tsf 1; controller c; state x1; input u; A = -1; B = 1;\n\
    premise x1 range -1 .. 1 { all = trap(-1, -1, 1, 1); }\n\
    rule R: x1 is all => A = -2;\n";

/// Evaluates `expr` as the value of a constant (which sees no signals).
fn eval(expr: &str) -> Result<Vec<f64>, String> {
    let (spec, diags) = check_source(&format!("{SPEC}const v = {expr};"));
    if let Some(e) = diags.iter().find(|d| d.is_error()) {
        return Err(e.message.clone());
    }
    let spec = spec.ok_or("no spec")?;
    let v = spec.consts.get("v").ok_or("no value")?;
    Ok(v.iter().copied().collect())
}

#[test]
fn precedence_and_associativity() {
    assert_eq!(eval("1 + 2 * 3").unwrap(), vec![7.0]);
    assert_eq!(eval("-2 ^ 2").unwrap(), vec![-4.0]);
    assert_eq!(eval("2 ^ 3 ^ 2").unwrap(), vec![512.0]);
    assert_eq!(eval("8 / 2 / 2").unwrap(), vec![2.0]);
    assert_eq!(eval("1 - 2 - 3").unwrap(), vec![-4.0]);
}

#[test]
fn matrices_blocks_transpose_and_indexing() {
    // Column-major storage: [1, 2; 3, 4] is stored as 1, 3, 2, 4.
    assert_eq!(eval("[1, 2; 3, 4]").unwrap(), vec![1.0, 3.0, 2.0, 4.0]);
    assert_eq!(eval("[1, 2; 3, 4]'").unwrap(), vec![1.0, 2.0, 3.0, 4.0]);
    assert_eq!(
        eval("[eye(2), [5; 6]]").unwrap(),
        vec![1.0, 0.0, 0.0, 1.0, 5.0, 6.0]
    );
    assert_eq!(eval("[1; 2; 3; 4][1..3]").unwrap(), vec![2.0, 3.0]);
    assert_eq!(eval("[1, 2; 3, 4][.., 1]").unwrap(), vec![2.0, 4.0]);
    assert_eq!(eval("[1, 2; 3, 4] * [1; 1]").unwrap(), vec![3.0, 7.0]);
    assert_eq!(eval("[1, 2] .* [3, 4]").unwrap(), vec![3.0, 8.0]);
    assert_eq!(eval("[1, 1; 0, 1] ^ 3").unwrap(), vec![1.0, 0.0, 3.0, 1.0]);
}

#[test]
fn builtins_agree_with_closed_forms() {
    let c = eval("cross([1; 0; 0], [0; 1; 0])").unwrap();
    assert_eq!(c, vec![0.0, 0.0, 1.0]);
    let s = eval("skew([1; 2; 3]) * [4; 5; 6] - cross([1; 2; 3], [4; 5; 6])").unwrap();
    assert!(s.iter().all(|v| v.abs() < 1e-15));
    let i = eval("inv([4, 7; 2, 6]) * [4, 7; 2, 6]").unwrap();
    assert!((i[0] - 1.0).abs() < 1e-14 && i[1].abs() < 1e-14 && (i[3] - 1.0).abs() < 1e-14);
    assert_eq!(eval("sinc(0)").unwrap(), vec![1.0]);
    assert!((eval("sinc(pi() / 2)").unwrap()[0] - 2.0 / std::f64::consts::PI).abs() < 1e-15);
    assert_eq!(eval("diag([1; 2])").unwrap(), vec![1.0, 0.0, 0.0, 2.0]);
    assert_eq!(
        eval("blkdiag(1, [2, 3])").unwrap(),
        vec![1.0, 0.0, 0.0, 2.0, 0.0, 3.0]
    );
    assert_eq!(eval("mean([1, 2, 3, 6])").unwrap(), vec![3.0]);
    assert_eq!(eval("zeros(2)").unwrap().len(), 2);
    assert_eq!(eval("norm([3; 4])").unwrap(), vec![5.0]);
}

#[test]
fn sinc_is_the_runtime_sinc() {
    // Both branches (|v| < 2^-13 and sin(v)/v), bit for bit.
    for v in [0.0, 1e-9, -1e-5, 1.2e-4, 0.3, -1.0, 2.5, 100.0] {
        let got = eval(&format!("sinc({v:e})")).unwrap()[0];
        assert_eq!(
            got.to_bits(),
            tsf_runtime::math::sinc(v).to_bits(),
            "sinc({v})"
        );
    }
}

#[test]
fn exprel_is_the_runtime_exprel() {
    // Both branches (|v| < 0.5: the series; (exp(v) - 1)/v), bit for bit.
    assert_eq!(eval("exprel(0)").unwrap(), vec![1.0]);
    assert_eq!(eval("exprel(-0)").unwrap(), vec![1.0]);
    for v in [
        0.0, 1e-9, -1e-5, 0.3, -0.49, 0.5, -0.5, -1.0, 2.5, 100.0, -800.0,
    ] {
        let got = eval(&format!("exprel({v:e})")).unwrap()[0];
        assert_eq!(
            got.to_bits(),
            tsf_runtime::math::exprel(v).to_bits(),
            "exprel({v})"
        );
    }
    let e = eval("exprel(1)").unwrap()[0];
    assert!((e - (std::f64::consts::E - 1.0)).abs() < 1e-15, "{e}");
    // Element-wise, like the other functions of one scalar.
    assert_eq!(eval("exprel([0, 0])").unwrap(), vec![1.0, 1.0]);
}

#[test]
fn errors_are_diagnostics() {
    assert!(eval("[1, 2] + [1; 2]")
        .unwrap_err()
        .contains("shape mismatch"));
    assert!(eval("inv([1, 2; 2, 4])").unwrap_err().contains("singular"));
    assert!(eval("[1; 2][2]").unwrap_err().contains("out of bounds"));
    assert!(eval("1 / 0").unwrap_err().contains("division by zero"));
    assert!(eval("eye(2, 3)").unwrap_err().contains("takes 1 argument"));
    assert!(eval("[1, 2; 3]").unwrap_err().contains("different widths"));
    assert!(eval("foo(1)").unwrap_err().contains("unknown function"));
}

#[test]
fn check_source_accepts_a_minimal_spec() {
    let src = "tsf 1; controller c; state x1; input u; A = -1; B = 1;\n\
               premise x1 range -1 .. 1 { all = trap(-1, -1, 1, 1); }\n\
               rule R: x1 is all => A = -2;";
    let (spec, diags) = check_source(src);
    assert!(diags.iter().all(|d| !d.is_error()), "{diags:?}");
    let spec = spec.expect("valid");
    assert_eq!((spec.n(), spec.m(), spec.rules.len()), (1, 1, 1));
}
