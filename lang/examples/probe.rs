use std::time::Instant;
fn main() {
    let path = std::env::args().nth(1).expect("path");
    let stack: usize = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(8 << 20);
    let bytes = std::fs::read(&path).expect("read");
    let text = String::from_utf8_lossy(&bytes).into_owned();
    let h = std::thread::Builder::new()
        .stack_size(stack)
        .spawn(move || {
            let t = Instant::now();
            let (spec, diags) = tsf_lang::check_source(&text);
            let dt = t.elapsed();
            let t2 = Instant::now();
            let out = tsf_lang::diag::render("p.tsf", &text, &diags, false);
            let dt2 = t2.elapsed();
            let shown: String = out.chars().take(3000).collect();
            println!("{shown}");
            eprintln!(
                "valid={} diags={} check={:?} render={:?} out_bytes={}",
                spec.is_some(),
                diags.len(),
                dt,
                dt2,
                out.len()
            );
        })
        .unwrap();
    h.join().unwrap();
}
