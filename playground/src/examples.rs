//! The page's examples: the shipped specs (`specs/*.tsf`), embedded when the
//! module is built (`build.rs`).

/// `(file name, text)` of each shipped spec, by file name.
pub const EXAMPLES: &[(&str, &str)] = include!(concat!(env!("OUT_DIR"), "/examples.rs"));

#[cfg(test)]
mod tests {
    #[test]
    fn the_shipped_specs_are_embedded() {
        let names: Vec<&str> = super::EXAMPLES.iter().map(|e| e.0).collect();
        assert!(names.contains(&"zhang2013_multiobjective.tsf"), "{names:?}");
        assert!(names.contains(&"xu2020_regional.tsf"), "{names:?}");
        assert!(super::EXAMPLES
            .iter()
            .all(|e| e.1.starts_with("tsf ") || e.1.contains("controller")));
    }
}
