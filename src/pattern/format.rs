//! Pattern files drapekit cannot read, recognised so that the error names their format rather
//! than calling them malformed JSON.

/// The name of a known pattern or drawing format that `bytes` (from a file named `path`) is in,
/// other than GarmentCode JSON: DXF (AutoCAD's drawing exchange format, which AAMA/ASTM pattern
/// files use), SVG and PDF.
pub fn foreign_format(path: &std::path::Path, bytes: &[u8]) -> Option<&'static str> {
    let head = String::from_utf8_lossy(&bytes[..bytes.len().min(512)]);
    let head = head.trim_start_matches('\u{feff}').trim_start();
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    // A text DXF opens with the group code 0 and SECTION; a binary one with its sentinel.
    let dxf_text = head.starts_with('0') && head.lines().nth(1).map(str::trim) == Some("SECTION");
    if dxf_text || head.starts_with("AutoCAD Binary DXF") || extension.as_deref() == Some("dxf") {
        return Some("DXF");
    }
    if head.starts_with("<svg") || (head.starts_with("<?xml") && head.contains("<svg")) {
        return Some("SVG");
    }
    if extension.as_deref() == Some("svg") {
        return Some("SVG");
    }
    if head.starts_with("%PDF") || extension.as_deref() == Some("pdf") {
        return Some("PDF");
    }
    None
}

/// The error's problem and fix for a pattern in `format`.
pub fn foreign_format_message(format: &str) -> (String, String) {
    (
        format!(
            "this is {} {format} file, which drapekit does not read: patterns must be \
             GarmentCode JSON specifications",
            if format.starts_with('S') { "an" } else { "a" }
        ),
        "export the pattern from GarmentCode (pygarment writes the JSON specification), or write \
         its panels and stitches in that format (see docs/src/patterns.md)"
            .to_string(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn formats_are_told_by_content_and_name() {
        let dxf = b"  0\nSECTION\n  2\nHEADER\n";
        assert_eq!(foreign_format(Path::new("a.txt"), dxf), Some("DXF"));
        assert_eq!(foreign_format(Path::new("shirt.DXF"), b"{}"), Some("DXF"));
        let svg = b"<?xml version=\"1.0\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\"/>";
        assert_eq!(foreign_format(Path::new("a.json"), svg), Some("SVG"));
        assert_eq!(
            foreign_format(Path::new("a.json"), b"%PDF-1.7"),
            Some("PDF")
        );
        assert_eq!(
            foreign_format(Path::new("a.json"), b"{\"pattern\": {}}"),
            None
        );
        // JSON whose first number is 0 is not taken for DXF.
        assert_eq!(foreign_format(Path::new("a.json"), b"0\n"), None);
    }
}
