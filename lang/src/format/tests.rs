use super::*;

fn fmt(s: &str) -> String {
    format_source(s).expect("formats")
}

#[test]
fn spacing_is_canonical() {
    assert_eq!(
        fmt("const  a=-1+2*x' ;  A(x)=[1,2;3 ,4];"),
        "const a = -1 + 2 * x';\nA(x) = [1, 2; 3, 4];\n"
    );
}
