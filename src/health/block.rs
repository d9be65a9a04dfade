//! The short block `drapekit run` prints at its end: seams, strain, the body, settling and
//! every warning, read from the summary so that a finished run folder says the same.

use crate::output::Summary;

/// The block's lines, without a trailing newline.
pub fn block(s: &Summary) -> String {
    let mut lines = vec!["result:".to_string()];
    let mut row = |name: &str, text: String| lines.push(format!("  {name:<9}{text}"));
    if s.seams > 0 {
        row(
            "seams",
            format!(
                "{} of {} closed (widest gap {:.1} mm)",
                s.seams_closed,
                s.seams,
                1000.0 * s.max_seam_gap_m.unwrap_or(0.0)
            ),
        );
    }
    row(
        "strain",
        format!(
            "{:.1}% largest at the last frame ({:.1}% during the run)",
            100.0 * s.last_frame_max_edge_strain,
            100.0 * s.max_edge_strain
        ),
    );
    if let Some(t) = &s.last_frame_thread_strain {
        row(
            "threads",
            format!(
                "{:.1}% largest, {:.2}% at the 99th percentile; shear {:.1}° (99th percentile)",
                100.0 * t.max,
                100.0 * t.p99,
                t.shear_p99_deg
            ),
        );
    }
    if let Some(deepest) = s.max_penetration_m {
        let last = match &s.body_show_through {
            Some(t) if t.particles + t.triangles > 0 => format!(
                "at the last frame it shows through {} of {} triangles",
                t.triangles, t.of_triangles
            ),
            _ => "at the last frame no cloth inside it".to_string(),
        };
        let resting = s
            .body_contacts
            .map_or(String::new(), |n| format!(", {n} particles resting on it"));
        row(
            "body",
            format!(
                "deepest penetration {:.1} mm during the run; {last}{resting}",
                1000.0 * deepest
            ),
        );
    }
    row(
        "settled",
        match &s.settled {
            Some(t) => format!(
                "yes, at frame {} (RMS speed {:.2e} m/s{})",
                t.frame,
                t.rms_speed_m_s,
                t.force_residual_rms.map_or(String::new(), |r| format!(
                    ", force residual {r:.2e} of the weight"
                ))
            ),
            None => format!(
                "no (RMS speed {} at the last frame)",
                s.last_frame_rms_speed_m_s
                    .map_or("unknown".to_string(), |v| format!("{v:.2e} m/s"))
            ),
        },
    );
    match s.warnings.len() {
        0 => row("warnings", "none".into()),
        n => {
            row("warnings", n.to_string());
            lines.extend(s.warnings.iter().map(|w| format!("    - {w}")));
        }
    }
    lines.join("\n")
}
