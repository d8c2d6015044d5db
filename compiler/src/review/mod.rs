//! `tsfc review`: one self-contained HTML page per design for a design
//! review (docs/review.md). The design is the certified report of
//! `tsfc compile` when it matches the spec, else the spec compiled again
//! ([`design`]); the spec's `simulate` scenario is run; the page holds the
//! claim, the certificate table, the gains and P, the membership functions,
//! the model-consistency map, the closed-loop plots and metrics, and the
//! generated files' hashes ([`page`]). Figures are inline SVG drawn by the
//! simulator's charts ([`figures`]), CSS is inline, there is no script and
//! no external reference; every text from the spec is escaped ([`html`]).
//! The same spec gives the same bytes (no timing is shown).

pub mod design;
pub mod figures;
pub mod html;
pub mod page;

use crate::util::error::Error;
use std::path::{Path, PathBuf};

pub use design::{Design, Origin};
pub use page::Scenario;

/// What [`review`] wrote.
#[derive(Debug)]
pub struct Written {
    /// The page's path, `OUT/<controller>.review.html`.
    pub path: PathBuf,
    /// Its size in bytes.
    pub bytes: usize,
    /// Where the design came from.
    pub origin: Origin,
    /// Why the scenario could not be run, if it could not.
    pub scenario_error: Option<String>,
}

/// The review page of the spec at `spec` as HTML text, with its design and
/// why the scenario could not be run (if it could not).
pub fn page(
    spec: &Path,
    report: Option<&Path>,
    out: &Path,
) -> Result<(String, Design, Option<String>), Error> {
    let design = design::design(spec, report, out)?;
    let scenario = if design.prepared.model.spec.simulate.is_some() {
        match crate::sim::simulate(&design.prepared, &crate::sim::Options::default()) {
            Ok(o) => Scenario::Ran(Box::new(o)),
            Err(e) => Scenario::Failed(e.message),
        }
    } else {
        Scenario::None
    };
    let html = page::render(&design, &scenario)?;
    let failed = match scenario {
        Scenario::Failed(why) => Some(why),
        _ => None,
    };
    Ok((html, design, failed))
}

/// Writes the review page of the spec at `spec` to `out/<controller>.review.html`
/// (atomically), taking the design from `report` or `out`'s report when it matches.
pub fn review(spec: &Path, report: Option<&Path>, out: &Path) -> Result<Written, Error> {
    let (html, design, scenario_error) = page(spec, report, out)?;
    let path = out.join(format!(
        "{}.review.html",
        design.prepared.model.spec.controller.node
    ));
    crate::util::output::write_atomic(&path, html.as_bytes())
        .map_err(|e| Error::usage(format!("cannot write `{}`: {e}", path.display())))?;
    Ok(Written {
        path,
        bytes: html.len(),
        origin: design.origin,
        scenario_error,
    })
}

impl Written {
    /// What was done, for the terminal: where the design came from, the
    /// scenario's failure if any, and the page written.
    pub fn summary(&self) -> String {
        let mut s = match &self.origin {
            Origin::Reused(r) => format!(
                "using the certified design of `{}` (same spec sha256; nothing solved)\n",
                r.display()
            ),
            Origin::Compiled(Some(why)) => format!("note: {why}; compiled the design\n"),
            Origin::Compiled(None) => String::new(),
        };
        if let Some(why) = &self.scenario_error {
            s.push_str(&format!("warning: the scenario could not be run: {why}\n"));
        }
        s.push_str(&format!(
            "  wrote                {} ({} bytes)\n",
            self.path.display(),
            self.bytes
        ));
        s
    }
}
