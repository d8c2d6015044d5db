//! `precision f32` is really f32 on a Cortex-M4F: the f32 builds of shipped
//! specs (premise expressions with `sinc` and `p' * p`, a mixed-trigger
//! sensor, Markov modes), with every float elementary function of the
//! runtime (`tsf_expf`, `tsf_atanf`, ...) kept as an entry point, are generated,
//! cross-compiled with arm-none-eabi-gcc (`-mcpu=cortex-m4 -mfpu=fpv4-sp-d16
//! -mfloat-abi=hard -Os`), linked against newlib from the entry points of the
//! controller and sensor files, and the image must hold no double-precision
//! routine. Skipped, with a message, when arm-none-eabi-gcc is not installed
//! (the flight audit, tests/audit/flight_audit.sh, checks every shipped spec).

use crate::common::{fresh_dir, spec_path, tsfc_binary};
use std::path::Path;
use std::process::Command;

const CFLAGS: [&str; 6] = [
    "-mcpu=cortex-m4",
    "-mthumb",
    "-mfloat-abi=hard",
    "-mfpu=fpv4-sp-d16",
    "-Os",
    "-std=c99",
];

/// Whether `name` is a double-precision routine: libgcc's soft-double
/// helpers and conversions, libm's double functions and kernels.
fn is_double_routine(name: &str) -> bool {
    const LIBM: [&str; 27] = [
        "exp", "expm1", "log", "log1p", "sqrt", "atan", "atan2", "sin", "cos", "tan", "fabs",
        "floor", "ceil", "pow", "hypot", "fmod", "scalbn", "ldexp", "frexp", "modf", "asin",
        "acos", "sinh", "cosh", "tanh", "trunc", "round",
    ];
    if let Some(rest) = name.strip_prefix("__aeabi_") {
        return rest.starts_with('d') || rest.ends_with("2d");
    }
    if let Some(rest) = name
        .strip_prefix("__ieee754_")
        .or_else(|| name.strip_prefix("__kernel_"))
    {
        return !rest.ends_with('f');
    }
    (name.starts_with("__") && name.contains("df") && name.ends_with(|c: char| c.is_ascii_digit()))
        || LIBM.contains(&name)
}

fn run(cmd: &mut Command, what: &str) -> String {
    let out = cmd.output().unwrap_or_else(|e| panic!("{what}: {e}"));
    assert!(
        out.status.success(),
        "{what} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The double-precision routines of the linked f32 build of shipped spec `name`.
fn double_routines(name: &str, dir: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(spec_path(&format!("{name}.tsf"))).expect("read spec");
    let text = match text.lines().find(|l| l.starts_with("precision ")) {
        Some(line) => text.replace(line, "precision f32;"),
        None => format!("{text}\nprecision f32;\n"),
    };
    let src = dir.join(format!("{name}.tsf"));
    std::fs::write(&src, text).expect("write spec");
    let gen = dir.join(format!("{name}-gen"));
    run(
        Command::new(tsfc_binary())
            .arg("compile")
            .arg(&src)
            .arg("--out")
            .arg(&gen),
        "tsfc compile (f32)",
    );
    let mut objects = Vec::new();
    let mut entries = Vec::new();
    for entry in std::fs::read_dir(&gen).expect("generated folder") {
        let c = entry.expect("entry").path();
        if c.extension().is_none_or(|e| e != "c") {
            continue;
        }
        let o = c.with_extension("o");
        run(
            Command::new("arm-none-eabi-gcc")
                .args(CFLAGS)
                .args([
                    "-ffunction-sections",
                    "-fdata-sections",
                    "-Wall",
                    "-Wextra",
                    "-Werror",
                    "-c",
                ])
                .arg("-I")
                .arg(&gen)
                .arg(&c)
                .arg("-o")
                .arg(&o),
            "arm-none-eabi-gcc -c",
        );
        if c.file_name().is_some_and(|f| f != "tsf_runtime.c") {
            let syms = run(
                Command::new("arm-none-eabi-nm")
                    .args(["-g", "--defined-only"])
                    .arg(&o),
                "arm-none-eabi-nm",
            );
            entries.extend(syms.lines().filter_map(|l| {
                let f: Vec<&str> = l.split_whitespace().collect();
                (f.len() == 3 && f[1] == "T").then(|| f[2].to_string())
            }));
        }
        objects.push(o);
    }
    entries.sort();
    assert!(!entries.is_empty(), "{name}: no entry point");
    let image = dir.join(format!("{name}.elf"));
    let mut link = Command::new("arm-none-eabi-gcc");
    link.args(CFLAGS)
        .args(["--specs=nosys.specs", "-nostartfiles", "-Wl,--gc-sections"])
        .arg(format!("-Wl,-e,{}", entries[0]));
    // Every float elementary function of the runtime too (the shipped specs
    // certified in f32 use sinc, sqrt and atan; gauss and about sets use expf).
    let float_functions = [
        "tsf_expf",
        "tsf_sqrtf",
        "tsf_atanf",
        "tsf_sinf",
        "tsf_cosf",
        "tsf_sincf",
        "tsf_exprelf",
        "tsf_fabsf",
    ];
    for e in entries.iter().map(String::as_str).chain(float_functions) {
        link.arg(format!("-Wl,-u,{e}"));
    }
    link.args(&objects).arg("-lm").arg("-o").arg(&image);
    run(&mut link, "arm-none-eabi-gcc (link)");
    let nm = run(
        Command::new("arm-none-eabi-nm").arg(&image),
        "arm-none-eabi-nm",
    );
    let all: Vec<String> = nm
        .lines()
        .filter_map(|l| l.split_whitespace().last())
        .map(str::to_string)
        .collect();
    // The image must hold the controller: the check would be empty otherwise.
    assert!(
        all.iter().any(|s| entries.contains(s)),
        "{name}: the image has none of its entry points"
    );
    all.into_iter().filter(|s| is_double_routine(s)).collect()
}

#[test]
fn the_double_routine_filter_knows_them() {
    for d in [
        "__aeabi_dmul",
        "__aeabi_f2d",
        "__aeabi_i2d",
        "__aeabi_ul2d",
        "__muldf3",
        "exp",
        "sqrt",
        "__ieee754_exp",
        "__kernel_sin",
    ] {
        assert!(is_double_routine(d), "{d}");
    }
    for f in [
        "__aeabi_fmul",
        "__aeabi_ul2f",
        "expf",
        "sqrtf",
        "__ieee754_sqrtf",
        "tsf_expf",
        "memcpy",
        "__mulsf3",
    ] {
        assert!(!is_double_routine(f), "{f}");
    }
}

#[test]
fn f32_builds_link_no_double_routine_on_cortex_m4f() {
    if Command::new("arm-none-eabi-gcc")
        .arg("--version")
        .output()
        .is_err()
    {
        println!("SKIP: arm-none-eabi-gcc is not installed (apt-get install gcc-arm-none-eabi libnewlib-arm-none-eabi)");
        return;
    }
    let dir = fresh_dir("f32-flight", "m4f");
    for name in [
        "zhang2013_multiobjective",
        "inverted_pendulum",
        "amrr2019_tsfc_design",
        "xue2024_markov_sampled",
    ] {
        let doubles = double_routines(name, &dir);
        assert!(
            doubles.is_empty(),
            "{name}: the f32 image links double-precision routines: {doubles:?}"
        );
        println!("{name}: f32 image for Cortex-M4F links no double-precision routine");
    }
}
