//! The sweep's comparison table: one row per scenario with its
//! certification, transmissions, inter-event times, energy, the declared
//! windowed norms and whether the run converged or failed; written as
//! Markdown, CSV and JSON.

use super::super::metrics::Metrics;
use serde::Serialize;

/// Format tag of the table's JSON.
pub const TABLE_FORMAT: &str = "tsfc-sweep/1";

/// Whose gains a row ran.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Gains {
    /// The compiled design (the spec's own law).
    Design,
    /// The compiled design: the scenario's law is the spec's own.
    Same,
    /// The given gains, certified for the scenario's law.
    GivenCertified,
    /// A design re-solved for the scenario's law.
    Resolved,
    /// The given gains, not certified for the scenario's law.
    GivenNotCertified,
    /// The compiled design's gains, not certified for the scenario's law.
    DesignNotCertified,
}

impl Gains {
    /// The gains of a row certified with a design of its own.
    pub fn own(given: bool) -> Gains {
        if given {
            Gains::GivenCertified
        } else {
            Gains::Resolved
        }
    }

    /// The gains of a refused row.
    pub fn fallback(given: bool) -> Gains {
        if given {
            Gains::GivenNotCertified
        } else {
            Gains::DesignNotCertified
        }
    }

    /// In a few words.
    pub fn describe(self) -> &'static str {
        match self {
            Gains::Design | Gains::Same => "compiled design",
            Gains::GivenCertified => "given gains",
            Gains::Resolved => "re-solved for this law",
            Gains::GivenNotCertified => "given gains (not certified here)",
            Gains::DesignNotCertified => "compiled design's gains (not certified here)",
        }
    }
}

/// One scenario's figures.
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Row {
    /// The spec's controller name.
    pub spec: String,
    /// The scenario's name (`design` for the spec's own law).
    pub scenario: String,
    /// The law as the simulator describes it.
    pub trigger: String,
    /// Whether a certificate covers this law.
    pub certified: bool,
    /// Why not (the compiler's refusal, first line).
    pub refused: Option<String>,
    /// Whose gains ran.
    pub gains: Gains,
    /// Transmissions to the actuators (including the one at t0).
    pub transmissions: Option<u64>,
    /// Mean time between transmissions (s).
    pub mean_inter_event_s: Option<f64>,
    /// Shortest time between transmissions (s).
    pub min_inter_event_s: Option<f64>,
    /// `integral ||u||^2 dt = sum_i integral u_i^2 dt`.
    pub energy: Option<f64>,
    /// Per declared column, the largest norm over the window.
    pub norms: Vec<Option<f64>>,
    /// Converged (metrics' rule: final norm within 5 % of `||x0||`).
    pub converged: bool,
    /// The run failed: an error, a non-finite state, divergence or leaving the premise region.
    pub failed: bool,
    /// Why it failed.
    pub why: Option<String>,
}

impl Row {
    /// The row of a run (`Err`: its error message).
    pub fn new(
        spec: &str,
        scenario: &str,
        refused: Option<String>,
        gains: Gains,
        run: Result<&Metrics, &str>,
        norms: Vec<Option<f64>>,
    ) -> Row {
        let mut row = Row {
            spec: spec.into(),
            scenario: scenario.into(),
            trigger: "-".into(),
            certified: refused.is_none(),
            refused,
            gains,
            transmissions: None,
            mean_inter_event_s: None,
            min_inter_event_s: None,
            energy: None,
            norms: norms.iter().map(|_| None).collect(),
            converged: false,
            failed: true,
            why: None,
        };
        match run {
            Ok(m) => {
                let failures = m.failures();
                row.trigger = m.trigger.clone();
                row.transmissions = Some(m.transmissions);
                row.mean_inter_event_s = m.mean_inter_event_s;
                row.min_inter_event_s = m.min_inter_event_s;
                row.energy = m.energy.is_finite().then_some(m.energy);
                row.norms = norms;
                row.converged = m.converged;
                row.failed = m.failed;
                row.why = (!failures.is_empty()).then(|| failures.join("; "));
            }
            Err(e) => row.why = Some(e.lines().next().unwrap_or("error").to_string()),
        }
        row
    }

    /// `yes`, or `NOT CERTIFIED`.
    fn certified_cell(&self) -> &'static str {
        if self.certified {
            "yes"
        } else {
            "NOT CERTIFIED"
        }
    }
}

/// The table of a sweep.
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Table {
    /// [`TABLE_FORMAT`].
    pub format: String,
    /// The first spec's controller name (file stem).
    pub name: String,
    /// Simulated span (s).
    pub time_s: (f64, f64),
    /// Window of the norm columns (s).
    pub window_s: (f64, f64),
    /// Norm columns: name and state group.
    pub columns: Vec<(String, String)>,
    /// The rows: each spec's design, then its scenarios.
    pub rows: Vec<Row>,
}

/// A number for the Markdown table.
/// Text safe inside a Markdown table cell: `|` escaped (trigger laws print
/// norms as `||e||`), line breaks as spaces.
fn md_cell(text: &str) -> String {
    text.replace('|', "\\|").replace('\n', " ")
}

fn cell(v: Option<f64>, digits: usize) -> String {
    match v {
        Some(v) if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e5) => format!("{v:.digits$e}"),
        Some(v) => format!("{v:.digits$}"),
        None => "-".into(),
    }
}

/// A number for the CSV: shortest round-trip digits, empty when absent.
fn csv_number(v: Option<f64>) -> String {
    let mut out = Vec::new();
    match v {
        Some(v) if super::super::csv::number(&mut out, v).is_ok() => {
            String::from_utf8_lossy(&out).into_owned()
        }
        _ => String::new(),
    }
}

/// A quoted CSV text field.
fn csv_text(s: &str) -> String {
    format!("\"{}\"", s.replace('"', "\"\""))
}

impl Table {
    /// Whether some row's run failed (`tsfc simulate --sweep` exits 4).
    pub fn any_failed(&self) -> bool {
        self.rows.iter().any(|r| r.failed)
    }

    /// The Markdown table, with the refusals and failures listed below it.
    pub fn markdown(&self) -> String {
        let mut s = format!(
            "# Sweep: `{}`\n\n{} rows over {} .. {} s; norm columns: largest Euclidean norm over {} .. {} s. \
             A row marked NOT CERTIFIED ran a triggering law that no certificate covers.\n\n",
            self.name,
            self.rows.len(),
            self.time_s.0,
            self.time_s.1,
            self.window_s.0,
            self.window_s.1
        );
        let mut head = vec![
            "spec",
            "scenario",
            "trigger",
            "certified",
            "gains",
            "transmissions",
            "mean T_i (s)",
            "min T_i (s)",
            "energy",
        ]
        .into_iter()
        .map(String::from)
        .collect::<Vec<_>>();
        head.extend(self.columns.iter().map(|(n, g)| format!("max ‖{g}‖ ({n})")));
        head.extend(["converged".into(), "failed".into()]);
        s.push_str(&format!("| {} |\n", head.join(" | ")));
        s.push_str(&format!("|{}\n", "---|".repeat(head.len())));
        for r in &self.rows {
            let mut cells = vec![
                r.spec.clone(),
                r.scenario.clone(),
                r.trigger.clone(),
                r.certified_cell().into(),
                r.gains.describe().into(),
                r.transmissions.map_or("-".into(), |t| t.to_string()),
                cell(r.mean_inter_event_s, 4),
                cell(r.min_inter_event_s, 4),
                cell(r.energy, 4),
            ];
            cells.extend(r.norms.iter().map(|v| cell(*v, 3)));
            cells.push(if r.converged { "yes" } else { "no" }.into());
            cells.push(if r.failed { "FAILED" } else { "no" }.into());
            let cells: Vec<String> = cells.iter().map(|c| md_cell(c)).collect();
            s.push_str(&format!("| {} |\n", cells.join(" | ")));
        }
        let refused: Vec<&Row> = self.rows.iter().filter(|r| !r.certified).collect();
        if !refused.is_empty() {
            s.push_str("\n## Not certified\n\n");
            for r in refused {
                s.push_str(&format!(
                    "- `{}` {}: {} (ran the {})\n",
                    r.spec,
                    r.scenario,
                    r.refused.as_deref().unwrap_or("refused"),
                    r.gains.describe()
                ));
            }
        }
        let failed: Vec<&Row> = self.rows.iter().filter(|r| r.failed).collect();
        if !failed.is_empty() {
            s.push_str("\n## Failed runs\n\n");
            for r in failed {
                s.push_str(&format!(
                    "- `{}` {}: {}\n",
                    r.spec,
                    r.scenario,
                    r.why.as_deref().unwrap_or("failed")
                ));
            }
        }
        s
    }

    /// The CSV table (one header line, one line per row).
    pub fn csv(&self) -> String {
        let mut s = String::from(
            "spec,scenario,trigger,certified,refused,gains,transmissions,mean_inter_event_s,min_inter_event_s,energy",
        );
        for (n, _) in &self.columns {
            s.push_str(&format!(",{}", csv_text(n)));
        }
        s.push_str(",converged,failed,why\n");
        for r in &self.rows {
            let mut cells = vec![
                csv_text(&r.spec),
                csv_text(&r.scenario),
                csv_text(&r.trigger),
                r.certified.to_string(),
                csv_text(r.refused.as_deref().unwrap_or("")),
                csv_text(r.gains.describe()),
                r.transmissions.map_or(String::new(), |t| t.to_string()),
                csv_number(r.mean_inter_event_s),
                csv_number(r.min_inter_event_s),
                csv_number(r.energy),
            ];
            cells.extend(r.norms.iter().map(|v| csv_number(*v)));
            cells.push(r.converged.to_string());
            cells.push(r.failed.to_string());
            cells.push(csv_text(r.why.as_deref().unwrap_or("")));
            s.push_str(&cells.join(","));
            s.push('\n');
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(certified: bool, failed: bool) -> Row {
        Row {
            spec: "c".into(),
            scenario: "periodic every = 2".into(),
            trigger: "periodic every 2 s".into(),
            certified,
            refused: (!certified).then(|| "not certified (\"x\")".into()),
            gains: if certified {
                Gains::GivenCertified
            } else {
                Gains::GivenNotCertified
            },
            transmissions: Some(6),
            mean_inter_event_s: Some(2.0),
            min_inter_event_s: Some(2.0),
            energy: Some(1.5e-7),
            norms: vec![Some(0.25)],
            converged: true,
            failed,
            why: failed.then(|| "diverged".into()),
        }
    }

    #[test]
    fn markdown_and_csv_mark_refusals_and_failures() {
        let t = Table {
            format: TABLE_FORMAT.into(),
            name: "c".into(),
            time_s: (0.0, 10.0),
            window_s: (5.0, 10.0),
            columns: vec![("s".into(), "x1".into())],
            rows: vec![row(true, false), row(false, true)],
        };
        let md = t.markdown();
        assert!(md.contains("| c | periodic every = 2 | periodic every 2 s | yes | given gains | 6 | 2.0000 | 2.0000 | 1.5000e-7 | 0.250 | yes | no |"), "{md}");
        assert!(md.contains("NOT CERTIFIED"));
        assert_eq!(
            md_cell("mixed ||e|| >= 0.5 ||s||\nx"),
            "mixed \\|\\|e\\|\\| >= 0.5 \\|\\|s\\|\\| x"
        );
        assert!(md.contains("## Not certified\n\n- `c` periodic every = 2: not certified (\"x\")"));
        assert!(md.contains("## Failed runs\n\n- `c` periodic every = 2: diverged"));
        assert!(t.any_failed());
        let csv = t.csv();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 3);
        assert!(lines[0].ends_with(",\"s\",converged,failed,why"));
        assert!(
            lines[2].contains("false,\"not certified (\"\"x\"\")\""),
            "{}",
            lines[2]
        );
        assert!(
            lines[1].contains(",6,2,2,1.5e-7,0.25,true,false,\"\""),
            "{}",
            lines[1]
        );
    }
}
