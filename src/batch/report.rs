//! `drapekit batch report DIR`: every item folder's summary in one table (`batch.csv`) and an
//! overview (`batch.md`: counts, failures by cause, time per item).

use super::item::{read_marker, Failure, DONE, ERROR_JSON, ITEM_JSON, PARTIAL};
use crate::atomic_file::write_atomic;
use crate::error::{Error, InputError};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;

/// The columns of `batch.csv`, in order; docs/src/batches.md says what each holds.
pub const COLUMNS: &[&str] = &[
    "id",
    "status",
    "error_kind",
    "error",
    "manifest_line",
    "scene",
    "garment",
    "fabric",
    "particle_distance_m",
    "backend",
    "integrator",
    "particles",
    "triangles",
    "frames",
    "substeps_per_frame",
    "simulated_seconds",
    "wall_seconds",
    "item_seconds",
    "attempts",
    "finite",
    "settled_frame",
    "max_edge_strain",
    "last_frame_max_edge_strain",
    "kinetic_energy_j",
    "seams",
    "seams_closed",
    "max_seam_gap_m",
    "max_penetration_m",
    "body_contacts",
];

/// What the report found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    /// One row per item folder, sorted by id, cells in [`COLUMNS`] order.
    pub rows: Vec<Vec<String>>,
    /// Hidden folders of items being built now, or abandoned by a killed run.
    pub partial: usize,
    /// Folders that are not items (no item.json, no marker), by name.
    pub ignored: Vec<String>,
}

/// The status of an item marked done whose summary.json is missing or does not read.
pub const DAMAGED: &str = "damaged";

impl Report {
    /// The cell of `column` in `row`.
    pub fn cell<'a>(&self, row: &'a [String], column: &str) -> &'a str {
        let k = COLUMNS
            .iter()
            .position(|c| *c == column)
            .expect("a known column");
        &row[k]
    }
}

/// Reads every item folder of `dir`, writes `batch.csv` and `batch.md` there, and returns the
/// report.
pub fn write(dir: &Path) -> Result<Report, Error> {
    let entries = std::fs::read_dir(dir).map_err(|e| {
        InputError::new(
            dir,
            "",
            format!("cannot read the batch folder: {e}"),
            "give the --out folder of `drapekit batch`",
        )
    })?;
    let mut report = Report::default();
    for entry in entries {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with(PARTIAL) {
            report.partial += 1;
        }
        if name.starts_with('.') || !entry.path().is_dir() {
            continue;
        }
        // Every item folder holds item.json (written before it is published) or its marker;
        // another folder is not the batch's.
        let path = entry.path();
        if !path.join(ITEM_JSON).is_file() && !path.join(DONE).is_file() {
            report.ignored.push(name);
            continue;
        }
        report.rows.push(row(&path, &name));
    }
    if report.rows.is_empty() && dir.join("summary.json").is_file() {
        return Err(InputError::new(
            dir,
            "",
            "is a run's output folder (it holds summary.json), not a batch's",
            "give the --out folder of `drapekit batch`",
        )
        .into());
    }
    report.ignored.sort();
    report.rows.sort();
    let mut csv = COLUMNS.join(",") + "\n";
    for r in &report.rows {
        let cells: Vec<String> = r.iter().map(|c| csv_cell(c)).collect();
        csv += &(cells.join(",") + "\n");
    }
    write_atomic(&dir.join("batch.csv"), csv.as_bytes())?;
    write_atomic(&dir.join("batch.md"), markdown(&report).as_bytes())?;
    Ok(report)
}

/// One item folder as a row.
fn row(path: &Path, id: &str) -> Vec<String> {
    let read = |name: &str| -> Value {
        std::fs::read(path.join(name))
            .ok()
            .and_then(|b| serde_json::from_slice(&b).ok())
            .unwrap_or(Value::Null)
    };
    let summary = read("summary.json");
    let item = read(ITEM_JSON);
    let failure: Option<Failure> = serde_json::from_value(read(ERROR_JSON)).ok();
    // Without a marker the folder was left by a transient failure: the next run redoes it.
    // Marked done without a summary that reads, it was damaged since.
    let status = match read_marker(path) {
        Some(m) if m.status == "ok" && summary.is_null() => DAMAGED.to_string(),
        Some(m) => m.status,
        None => "unfinished".into(),
    };
    let failure = failure.or_else(|| {
        (status == DAMAGED).then(|| Failure {
            kind: DAMAGED.into(),
            exit_code: 2,
            message: "summary.json is missing or not JSON: delete the folder, and the next \
                      run redoes the item"
                .into(),
        })
    });
    let text = |v: &Value| match v {
        Value::Null => String::new(),
        Value::String(s) => s.clone(),
        other => other.to_string(),
    };
    // The pattern's file name, else the scene's.
    let files = item["files"].as_array().cloned().unwrap_or_default();
    let pattern = files.iter().find(|f| f["role"] == "pattern");
    let source = pattern.map_or_else(|| text(&item["scene"]), |f| text(&f["path"]));
    let garment = Path::new(&source)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    COLUMNS
        .iter()
        .map(|&c| match c {
            "id" => id.to_string(),
            "status" => status.clone(),
            "error_kind" => failure.as_ref().map_or(String::new(), |f| f.kind.clone()),
            // On one line, so that line-based tools can read the table.
            "error" => failure.as_ref().map_or(String::new(), |f| {
                f.message.split_whitespace().collect::<Vec<_>>().join(" ")
            }),
            "manifest_line"
            | "scene"
            | "fabric"
            | "particle_distance_m"
            | "item_seconds"
            | "attempts" => text(&item[c]),
            "garment" => garment.clone(),
            "settled_frame" => text(&summary["settled"]["frame"]),
            _ => text(&summary[c]),
        })
        .collect()
}

/// RFC 4180: quote a cell holding a comma, quote or line break, doubling its quotes.
fn csv_cell(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Nearest-rank percentile of sorted values.
fn percentile(sorted: &[f64], p: f64) -> f64 {
    let rank = ((p / 100.0) * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1]
}

fn markdown(report: &Report) -> String {
    let mut by_status: BTreeMap<&str, usize> = BTreeMap::new();
    let mut causes: BTreeMap<String, Vec<&str>> = BTreeMap::new();
    let mut times = Vec::new();
    for r in &report.rows {
        *by_status.entry(report.cell(r, "status")).or_default() += 1;
        let kind = report.cell(r, "error_kind");
        if !kind.is_empty() {
            causes
                .entry(kind.to_string())
                .or_default()
                .push(report.cell(r, "id"));
        }
        // A time that is not a finite, non-negative number (a hand-edited or damaged item
        // file) is left out rather than turning every statistic into NaN.
        let time = report.cell(r, "item_seconds").parse::<f64>();
        if let Some(t) = time.ok().filter(|t| t.is_finite() && *t >= 0.0) {
            times.push(t);
        }
    }
    let mut md = String::from(
        "# Batch report\n\n| items | ok | failed | unfinished | damaged |\n|---|---|---|---|---|\n",
    );
    let count = |s: &str| by_status.get(s).copied().unwrap_or(0);
    md += &format!(
        "| {} | {} | {} | {} | {} |\n\n",
        report.rows.len(),
        count("ok"),
        count("failed"),
        count("unfinished"),
        count(DAMAGED)
    );
    md += "\"unfinished\": the folder of a transient failure (GPU, I/O), which the next run \
           redoes.\n";
    if count(DAMAGED) > 0 {
        md += &format!(
            "{} item(s) marked done have no summary.json that reads (\"{DAMAGED}\"): delete \
             their folders, and the next run redoes them.\n",
            count(DAMAGED)
        );
    }
    if !report.ignored.is_empty() {
        md += &format!(
            "Not item folders (no item.json), left out: {}.\n",
            report.ignored.join(", ")
        );
    }
    if report.partial > 0 {
        md += &format!(
            "{} hidden `.partial~` folder(s): items being built now, or abandoned by a killed \
             run (the next run of their shard removes them).\n",
            report.partial
        );
    }
    md += "\n## Failures by cause\n\n";
    if causes.is_empty() {
        md += "None.\n";
    } else {
        md += "| cause | items | ids |\n|---|---|---|\n";
        for (kind, ids) in &causes {
            md += &format!("| {kind} | {} | {} |\n", ids.len(), ids.join(", "));
        }
    }
    md += "\n## Time per item\n\n";
    if times.is_empty() {
        md += "No item has a recorded time.\n";
    } else {
        times.sort_by(f64::total_cmp);
        let total: f64 = times.iter().sum();
        md += "Wall time of each item (load, model, simulation, files; all attempts), in s.\n\n\
               | items | mean | p50 | p90 | p99 | max | total |\n|---|---|---|---|---|---|---|\n";
        md += &format!(
            "| {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.1} |\n",
            times.len(),
            total / times.len() as f64,
            percentile(&times, 50.0),
            percentile(&times, 90.0),
            percentile(&times, 99.0),
            times[times.len() - 1],
            total
        );
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_rank_percentiles() {
        let v: Vec<f64> = (1..=10).map(f64::from).collect();
        assert_eq!(percentile(&v, 50.0), 5.0);
        assert_eq!(percentile(&v, 90.0), 9.0);
        assert_eq!(percentile(&v, 99.0), 10.0);
        assert_eq!(percentile(&[3.0], 50.0), 3.0);
    }

    #[test]
    fn item_times_that_are_not_finite_are_left_out_of_the_statistics() {
        let row = |id: &str, seconds: &str| {
            let mut r = vec![String::new(); COLUMNS.len()];
            let at = |c: &str| COLUMNS.iter().position(|x| *x == c).unwrap();
            r[at("id")] = id.into();
            r[at("status")] = "ok".into();
            r[at("item_seconds")] = seconds.into();
            r
        };
        let report = Report {
            rows: vec![
                row("a", "2.0"),
                row("b", "NaN"),
                row("c", "inf"),
                row("d", "-1"),
            ],
            partial: 0,
            ignored: Vec::new(),
        };
        let md = markdown(&report);
        assert!(
            md.contains("| 1 | 2.00 | 2.00 | 2.00 | 2.00 | 2.00 | 2.0 |"),
            "{md}"
        );
        assert!(!md.contains("NaN") && !md.contains("| inf"), "{md}");
    }

    #[test]
    fn csv_cells_are_quoted_only_when_needed() {
        assert_eq!(csv_cell("plain"), "plain");
        assert_eq!(csv_cell("a,b"), "\"a,b\"");
        assert_eq!(csv_cell("say \"x\"\nfix"), "\"say \"\"x\"\"\nfix\"");
    }
}
