//! Previews: the renderer draws what the camera predicts, strain measures stretch, seam lines
//! show, a CPU-backend run can be previewed from the command line, and a run writes its
//! previews as it goes and an animation at the end. Colours, legends and the golden image are
//! in `preview_colors.rs`.

mod common;

use drapekit::preview::{render, triangle_strain, CameraPreset};
use glam::{Vec3, Vec4Swizzles};

#[test]
fn the_sheet_covers_the_rectangle_its_corners_project_to() {
    let Some(ctx) = common::gpu() else { return };
    let red = Vec3::new(0.9, 0.05, 0.05);
    let mesh = common::sheet(red);
    let (w, h) = (320u32, 240u32);
    let (lo, hi) = (Vec3::new(-0.5, 1.0, 0.0), Vec3::new(0.5, 1.6, 0.0));
    let camera = CameraPreset::Front.framing(lo, hi, w as f32 / h as f32);
    let pixels = render(ctx, &[mesh], &camera, w, h).unwrap();
    assert_eq!(pixels.len(), (4 * w * h) as usize);
    // Where the corners land in pixels (y down).
    let vp = camera.view_proj(w as f32 / h as f32);
    let to_px = |p: Vec3| {
        let c = vp * p.extend(1.0);
        let ndc = c.xyz() / c.w;
        (
            (ndc.x + 1.0) * 0.5 * w as f32,
            (1.0 - ndc.y) * 0.5 * h as f32,
        )
    };
    let (x0, y1) = to_px(lo);
    let (x1, y0) = to_px(hi);
    // A pixel is the sheet's when red dominates (the background is grey, the sheet lit red).
    let is_sheet = |x: u32, y: u32| {
        let k = 4 * (y * w + x) as usize;
        let (r, g, b) = (pixels[k] as i32, pixels[k + 1] as i32, pixels[k + 2] as i32);
        r > g + 40 && r > b + 40
    };
    let (mut inside, mut inside_hit, mut outside_hit) = (0, 0, 0);
    for y in 0..h {
        for x in 0..w {
            let (fx, fy) = (x as f32 + 0.5, y as f32 + 0.5);
            // One pixel of slack at the edges, where the 2×2 supersampling blends.
            let strictly_in = fx > x0 + 1.0 && fx < x1 - 1.0 && fy > y0 + 1.0 && fy < y1 - 1.0;
            let strictly_out = fx < x0 - 1.0 || fx > x1 + 1.0 || fy < y0 - 1.0 || fy > y1 + 1.0;
            if strictly_in {
                inside += 1;
                inside_hit += is_sheet(x, y) as u32;
            } else if strictly_out {
                outside_hit += is_sheet(x, y) as u32;
            }
        }
    }
    assert!(inside > 1000, "the sheet projects to {inside} pixels");
    assert_eq!(
        inside_hit, inside,
        "sheet pixels missing inside its rectangle"
    );
    assert_eq!(outside_hit, 0, "sheet pixels outside its rectangle");
}

#[test]
fn strain_of_a_stretched_sheet_is_its_stretch() {
    let rest = common::sheet(Vec3::ONE);
    // 10% along x, 0% along y: the largest principal stretch is 1.1.
    let now: Vec<Vec3> = rest
        .positions
        .iter()
        .map(|p| Vec3::new(1.1 * p.x, p.y, p.z))
        .collect();
    let s = triangle_strain(&rest.positions, &now, &rest.triangles);
    for v in s {
        // One f32 rounding of O(1) coordinates per edge: ~1e-7 relative; 1e-5 is ample.
        assert!((v - 0.1).abs() < 1e-5, "{v}");
    }
    // A rigid rotation has no strain.
    let r = glam::Quat::from_rotation_y(0.7);
    let turned: Vec<Vec3> = rest.positions.iter().map(|p| r * *p).collect();
    for v in triangle_strain(&rest.positions, &turned, &rest.triangles) {
        assert!(v.abs() < 1e-5, "{v}");
    }
}

#[test]
fn a_cpu_run_can_be_previewed() {
    // The CPU backend runs; the preview makes its own device (the fallback adapter here).
    if common::gpu().is_none() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("drapekit-preview-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let bin = env!("CARGO_BIN_EXE_drapekit");
    let run = std::process::Command::new(bin)
        .args([
            "run",
            common::fixture("scenes/drape_sphere.toml")
                .to_str()
                .unwrap(),
        ])
        .args([
            "--backend",
            "cpu",
            "--frames",
            "6",
            "--out",
            dir.join("run").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let png = dir.join("p.png");
    let out = std::process::Command::new(bin)
        .args([
            "preview",
            dir.join("run").to_str().unwrap(),
            "--adapter",
            "fallback",
        ])
        .args([
            "--size",
            "200x150",
            "--mode",
            "strain",
            "--out",
            png.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(&png).unwrap();
    // PNG signature, then the IHDR chunk's width and height.
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    assert_eq!(u32::from_be_bytes(bytes[16..20].try_into().unwrap()), 200);
    assert_eq!(u32::from_be_bytes(bytes[20..24].try_into().unwrap()), 150);
    // A frame that is not there is bad input, exit 2.
    let missing = std::process::Command::new(bin)
        .args([
            "preview",
            dir.join("run").to_str().unwrap(),
            "--frame",
            "999",
        ])
        .args(["--out", dir.join("q.png").to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(missing.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("has no frame 999"));
    // A .gif holds every frame (the run wrote 0 and 6), so --frame with one is bad input.
    let preview = |extra: &[&str]| {
        std::process::Command::new(bin)
            .args(["preview", dir.join("run").to_str().unwrap()])
            .args(["--adapter", "fallback", "--size", "64x48"])
            .args(extra)
            .output()
            .unwrap()
    };
    let gif = dir.join("run.gif");
    let out = preview(&["--mode", "penetration", "--out", gif.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    use image::AnimationDecoder;
    let frames = image::codecs::gif::GifDecoder::new(std::io::BufReader::new(
        std::fs::File::open(&gif).unwrap(),
    ))
    .unwrap()
    .into_frames()
    .collect_frames()
    .unwrap();
    assert_eq!(frames.len(), 2);
    assert_eq!(frames[0].buffer().dimensions(), (64, 48));
    let both = preview(&["--frame", "6", "--out", gif.to_str().unwrap()]);
    assert_eq!(both.status.code(), Some(2));
    // A run whose summary lists no frames has nothing to animate: bad input, no empty GIF.
    let summary = dir.join("run/summary.json");
    let mut s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&summary).unwrap()).unwrap();
    s["outputs"] = serde_json::json!([]);
    std::fs::write(&summary, s.to_string()).unwrap();
    let empty = dir.join("empty.gif");
    let out = preview(&["--out", empty.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("holds no frame"));
    assert!(!empty.exists());
    // A summary whose fps is not a rate: frame times would be infinite (GIF delays of minutes).
    s["fps"] = serde_json::json!(0.0);
    std::fs::write(&summary, s.to_string()).unwrap();
    let out = preview(&["--out", dir.join("zero-fps.png").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a positive number"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn seam_lines_are_dark_thin_and_on_top() {
    let Some(ctx) = common::gpu() else { return };
    let white = Vec3::splat(0.8);
    let mesh = common::sheet(white);
    let (w, h) = (320u32, 240u32);
    let (lo, hi) = (Vec3::new(-0.5, 1.0, 0.0), Vec3::new(0.5, 1.6, 0.0));
    let camera = CameraPreset::Front.framing(lo, hi, w as f32 / h as f32);
    // A seam along the sheet's middle row (row 6 of 13, y = 1.3), particle to particle.
    let row: Vec<[u32; 2]> = (0..20).map(|i| [6 * 21 + i, 6 * 21 + i + 1]).collect();
    let ribbons = drapekit::preview::seam_ribbons(&mesh.positions, &row, &camera, h, 2.0);
    let pixels = render(ctx, &[mesh, ribbons], &camera, w, h).unwrap();
    let vp = camera.view_proj(w as f32 / h as f32);
    let c = vp * Vec3::new(0.0, 1.3, 0.0).extend(1.0);
    let (x, y) = (
        ((c.x / c.w + 1.0) * 0.5 * w as f32) as u32,
        ((1.0 - c.y / c.w) * 0.5 * h as f32) as u32,
    );
    let lum = |x: u32, y: u32| {
        let k = 4 * (y * w + x) as usize;
        (pixels[k] as u32 + pixels[k + 1] as u32 + pixels[k + 2] as u32) / 3
    };
    // Some row within a pixel of the line is dark (the lit sheet is ~200), and 4 px away it
    // is the sheet again: the line is drawn over the cloth, and thin.
    let darkest = (y.saturating_sub(1)..=y + 1)
        .map(|y| lum(x, y))
        .min()
        .unwrap();
    assert!(darkest < 80, "seam pixel luminance {darkest}");
    assert!(lum(x, y - 4) > 150 && lum(x, y + 4) > 150);
}

#[test]
fn a_run_writes_previews_every_n_frames_and_an_animation() {
    if common::gpu().is_none() {
        return;
    }
    let path = common::fixture("scenes/drape_sphere.toml");
    let text = std::fs::read_to_string(&path).unwrap().replace(
        "obj = true\nevery = 6",
        "obj = true\nevery = 3\npreview_every = 6\npreview_modes = [\"fabric\", \"penetration\"]\n\
         previews = [\"strain\"]\n\n[preview]\nsize = [160, 120]\nanimation = \"gif\"\n\
         animation_size = [96, 72]\ncamera = { eye = [1.5, 1.5, 2.5], target = [0.0, 0.3, 0.0], fov_deg = 35 }",
    );
    let dir = std::env::temp_dir().join(format!("drapekit-preview-run-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, text).unwrap();
    // A frame left by an earlier, longer run in the same folder is not this run's: the run is
    // refused without --overwrite (tests/run_folder.rs), and with it the frame goes.
    std::fs::create_dir_all(dir.join("run")).unwrap();
    std::fs::write(dir.join("run/frame_0099.obj"), "v 0 0 0\n").unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_drapekit"))
        .args([
            "run",
            scene.to_str().unwrap(),
            "--backend",
            "cpu",
            "--frames",
            "12",
        ])
        .args([
            "--adapter",
            "fallback",
            "--overwrite",
            "--out",
            dir.join("run").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let run = dir.join("run");
    assert!(!run.join("frame_0099.obj").exists());
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(run.join("summary.json")).unwrap()).unwrap();
    let outputs: Vec<&str> = (summary["outputs"].as_array().unwrap().iter())
        .map(|v| v.as_str().unwrap())
        .collect();
    let mut want = vec![];
    for f in [0, 6, 12] {
        for m in ["fabric", "penetration"] {
            want.push(format!("preview_{m}_{f:04}.png"));
        }
    }
    want.push("preview_strain.png".into());
    want.push("preview.gif".into());
    for name in &want {
        assert!(
            outputs.contains(&name.as_str()),
            "{name} not in {outputs:?}"
        );
        assert!(run.join(name).is_file(), "{name}");
    }
    assert!(
        !outputs.contains(&"preview_fabric_0003.png"),
        "off the preview schedule"
    );
    // The animation: every frame this run wrote (0, 3, …, 12), 96×72, each shown 3/24 s.
    let gif = image::codecs::gif::GifDecoder::new(std::io::BufReader::new(
        std::fs::File::open(run.join("preview.gif")).unwrap(),
    ))
    .unwrap();
    use image::AnimationDecoder;
    let frames = gif.into_frames().collect_frames().unwrap();
    assert_eq!(frames.len(), 5);
    assert_eq!(frames[0].buffer().dimensions(), (96, 72));
    let (num, den) = frames[0].delay().numer_denom_ms();
    // GIF stores delays in centiseconds: 125 ms is kept as 120 or 130.
    assert!(
        (num as f32 / den as f32 - 125.0).abs() <= 5.0,
        "{num}/{den} ms"
    );
    // The cloth rests on the sphere by frame 12: penetration colours show green (beyond the
    // thickness) at least; a cloth all in one colour or none would mean no distances.
    let img = image::open(run.join("preview_penetration_0012.png"))
        .unwrap()
        .to_rgba8();
    let green = img
        .pixels()
        .filter(|p| p[1] as i32 > p[0] as i32 + 30 && p[1] as i32 > p[2] as i32 + 30)
        .count();
    assert!(green > 50, "{green} green pixels");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_run_stopped_before_its_summary_is_named_as_such() {
    // A run killed mid-way leaves frames and no summary.json: exit 2 with what happened and
    // what to do, not an I/O error on a missing file.
    let dir = std::env::temp_dir().join(format!("drapekit-killed-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(
        common::fixture("meshes/folded_strip.obj"),
        dir.join("frame_0000.obj"),
    )
    .unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_drapekit"))
        .args(["preview", dir.to_str().unwrap(), "--out"])
        .arg(dir.join("p.png"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("it was stopped before it finished"),
        "{stderr}"
    );
    assert!(stderr.contains("drapekit resume"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_checker_outside_its_stated_range_is_refused() {
    // 0.001 to 10 m, as the message and the scene's checker_m say: 0.0009 and 1e-9 were let
    // through (a checker finer than a pixel). Refused before the run folder is read.
    for bad in ["0.0009", "1e-9", "11", "NaN"] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_drapekit"))
            .args(["preview", "no-such-run", "--checker", bad, "--out", "x.png"])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{bad}: {stderr}");
        assert!(stderr.contains("from 0.001 to 10"), "{bad}: {stderr}");
    }
}

#[test]
fn a_frame_0_of_another_cloth_is_named_as_such_for_strain() {
    // Frame 0 with one vertex more than the frame drawn: the folder mixes two runs' frames.
    // It used to say to rerun so that frame 0 is written, though it was there.
    let dir = std::env::temp_dir().join(format!("drapekit-mixed-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_drapekit"))
        .args([
            "run",
            "--backend",
            "cpu",
            "--quiet",
            "--frames",
            "2",
            "--out",
        ])
        .arg(&dir)
        .arg(common::fixture("scenes/hanging_cloth.toml"))
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let first = dir.join("frame_0000.obj");
    let text = std::fs::read_to_string(&first).unwrap();
    std::fs::write(&first, format!("v 0 0 0\n{text}")).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_drapekit"))
        .args([
            "preview",
            dir.to_str().unwrap(),
            "--mode",
            "strain",
            "--out",
        ])
        .arg(dir.join("p.png"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("they are not one run's"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}
