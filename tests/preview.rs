//! Previews: the renderer draws what the camera predicts, strain colours measure stretch and
//! come out of the renderer as the colour map says, the legend is drawn, a golden image still
//! matches, and a CPU-backend run can be previewed from the command line in every mode.

mod common;

use drapekit::gpu::AdapterChoice;
use drapekit::preview::{
    draw_legend, render, srgb_byte, strain_legend, strain_ramp, triangle_strain, CameraChoice,
    CameraPreset, ColorMode, DrawMesh, Look, Previewer,
};
use glam::{Vec3, Vec4Swizzles};

/// A 1 m × 0.6 m sheet in the xy plane at z = 0, 20 × 12 quads.
fn sheet(color: Vec3) -> DrawMesh {
    let (nx, ny) = (21u32, 13u32);
    let mut m = DrawMesh::default();
    for j in 0..ny {
        for i in 0..nx {
            m.positions.push(Vec3::new(
                i as f32 / (nx - 1) as f32 - 0.5,
                0.6 * j as f32 / (ny - 1) as f32 + 1.0,
                0.0,
            ));
            m.colors.push(color);
        }
    }
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            let a = j * nx + i;
            m.triangles.push([a, a + 1, a + nx + 1]);
            m.triangles.push([a, a + nx + 1, a + nx]);
        }
    }
    m
}

#[test]
fn the_sheet_covers_the_rectangle_its_corners_project_to() {
    let Some(ctx) = common::gpu() else { return };
    let red = Vec3::new(0.9, 0.05, 0.05);
    let mesh = sheet(red);
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
    let rest = sheet(Vec3::ONE);
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
    let _ = std::fs::remove_dir_all(&dir);
}

/// A temporary run folder holding `frames` as `frame_NNNN.obj` (positions and triangles only).
fn run_folder(name: &str, frames: &[(u32, &DrawMesh)]) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("drapekit-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (n, m) in frames {
        let mut text = String::new();
        for p in &m.positions {
            text += &format!("v {} {} {}\n", p.x, p.y, p.z);
        }
        for t in &m.triangles {
            text += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
        }
        std::fs::write(dir.join(format!("frame_{n:04}.obj")), text).unwrap();
    }
    dir
}

/// The front camera's lighting of a surface facing it (+z), as `shade.wgsl` computes it:
/// ambient 0.22, key 0.68·(n·key), fill 0.22·(n·fill).
fn facing_light() -> f32 {
    let key = Vec3::new(-0.45, 0.75, 0.6).normalize();
    let fill = Vec3::new(0.7, 0.2, 0.45).normalize();
    0.22 + 0.68 * key.z + 0.22 * fill.z
}

#[test]
fn strain_colours_of_a_stretched_sheet_follow_the_colour_map() {
    if common::gpu().is_none() {
        return;
    }
    // The left half stretched 5% along x, the right half 15% (continuous at x = 0): with
    // strain_max 20% the halves sit at a quarter and three quarters of the colour map.
    let rest = sheet(Vec3::ONE);
    let mut now = rest.clone();
    for p in &mut now.positions {
        p.x *= if p.x < 0.0 { 1.05 } else { 1.15 };
    }
    let dir = run_folder("strain-map", &[(0, &rest), (1, &now)]);
    let mut previewer = Previewer::new(&dir, None, 24.0, &AdapterChoice::Fallback).unwrap();
    let (w, h) = (200u32, 150u32);
    let look = Look {
        camera: CameraChoice::Preset(CameraPreset::Front),
        mode: ColorMode::Strain,
        size: (w, h),
        strain_max: 0.2,
        seams: false,
        legend: false,
        colors: Vec::new(),
        checker: 0.0,
    };
    let pixels = previewer.image(Some(1), &look, None).unwrap();
    // The sheet spans x in [-0.525, 0.575] at y 1.0..1.6; sample well inside each half.
    let camera = CameraPreset::Front.framing(
        Vec3::new(-0.525, 1.0, 0.0),
        Vec3::new(0.575, 1.6, 0.0),
        w as f32 / h as f32,
    );
    let vp = camera.view_proj(w as f32 / h as f32);
    let pixel_at = |p: Vec3| {
        let c = vp * p.extend(1.0);
        let ndc = c.xyz() / c.w;
        let (x, y) = (
            ((ndc.x + 1.0) * 0.5 * w as f32) as u32,
            ((1.0 - ndc.y) * 0.5 * h as f32) as u32,
        );
        let k = 4 * (y * w + x) as usize;
        [pixels[k], pixels[k + 1], pixels[k + 2]]
    };
    for (x, t) in [(-0.25, 0.25), (0.3, 0.75)] {
        let got = pixel_at(Vec3::new(x, 1.3, 0.0));
        let want = (strain_ramp(t) * facing_light()).to_array().map(srgb_byte);
        // The GPU lights in f32 and encodes sRGB in its own rounding; a flat region then
        // averages four equal samples. 3 of 255 covers both roundings with room to spare,
        // while the map's neighbouring strain of 1% (t ± 0.05) moves a channel by ≥ 10.
        for c in 0..3 {
            assert!(
                (got[c] as i32 - want[c] as i32).abs() <= 3,
                "strain {t}×20% at x = {x}: rendered {got:?}, colour map {want:?}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_legend_shows_the_colour_map_and_its_labels() {
    let (w, h) = (1280u32, 960u32);
    let background = 180u8;
    let mut pixels = vec![background; (4 * w * h) as usize];
    let legend = strain_legend(0.2);
    let b = draw_legend(&mut pixels, w, h, &legend);
    let at = |x: u32, y: u32| {
        let k = 4 * (y * w + x) as usize;
        [pixels[k], pixels[k + 1], pixels[k + 2]]
    };
    // In the top-right corner, and tall enough to read (a third of the image or more).
    assert!(b.panel.2 <= w && b.panel.0 > w / 2 && b.panel.1 < h / 10);
    assert!(b.bar.3 - b.bar.1 >= h / 3);
    // The bar's top row is the map's 20% colour, its bottom row 0%, its middle 10%.
    let mid_x = (b.bar.0 + b.bar.2) / 2;
    let exact = |t: f32| strain_ramp(t).to_array().map(srgb_byte);
    assert_eq!(at(mid_x, b.bar.1), exact(1.0));
    assert_eq!(at(mid_x, b.bar.3 - 1), exact(0.0));
    let middle = at(mid_x, (b.bar.1 + b.bar.3 - 1) / 2);
    for (got, want) in middle.iter().zip(exact(0.5)) {
        // The middle row is within half a row of t = 0.5: a fraction of a level.
        assert!((*got as i32 - want as i32).abs() <= 2);
    }
    // Labels: dark ink right of the bar, in rows near each of the five ticks.
    let ink = |x: u32, y: u32| at(x, y).iter().all(|&v| v < 40);
    for k in 0..5 {
        let y = b.bar.1 + (b.bar.3 - 1 - b.bar.1) * (4 - k) / 4;
        let rows = y.saturating_sub(12)..(y + 12).min(h);
        let found = rows
            .flat_map(|y| (b.bar.2 + 4..b.panel.2).map(move |x| (x, y)))
            .any(|(x, y)| ink(x, y));
        assert!(found, "no label at tick {k}");
    }
    // Nothing is drawn outside the panel.
    let outside = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .filter(|&(x, y)| x < b.panel.0 || x >= b.panel.2 || y < b.panel.1 || y >= b.panel.3)
        .any(|(x, y)| at(x, y) != [background; 3]);
    assert!(!outside, "the legend drew outside its panel");
    // At 4K the text scales up: the panel grows with the image.
    let (w4, h4) = (3840u32, 2160u32);
    let mut big = vec![background; (4 * w4 * h4) as usize];
    let b4 = draw_legend(&mut big, w4, h4, &legend);
    assert!(b4.panel.3 - b4.panel.1 > 2 * (b.panel.3 - b.panel.1) * 2 / 3);
}

/// The golden image's scene: a sheet curved into a half-pipe, coloured along x by the strain
/// map, in front of a coarse sphere, seen three-quarter, with the strain legend.
fn golden_scene() -> Vec<DrawMesh> {
    let mut sheet = sheet(Vec3::ONE);
    for (p, c) in sheet.positions.iter_mut().zip(&mut sheet.colors) {
        *c = strain_ramp(p.x + 0.5);
        p.z = 0.3 * (1.0 - 4.0 * p.x * p.x);
    }
    let mut sphere = DrawMesh::default();
    let (rings, segments) = (8u32, 12u32);
    for i in 0..=rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            let d = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            sphere.positions.push(Vec3::new(0.0, 1.3, -0.2) + 0.25 * d);
            sphere.colors.push(drapekit::preview::BODY);
        }
    }
    for i in 0..rings {
        for j in 0..segments {
            let (a, b) = (i * segments + j, i * segments + (j + 1) % segments);
            let (c, d) = (a + segments, b + segments);
            sphere.triangles.push([a, c, b]);
            sphere.triangles.push([b, c, d]);
        }
    }
    vec![sheet, sphere]
}

#[test]
fn a_fixed_scene_renders_as_its_golden_image() {
    let Some(ctx) = common::gpu() else { return };
    let (w, h) = (160u32, 120u32);
    let meshes = golden_scene();
    let camera = CameraPreset::ThreeQuarter.framing(
        Vec3::new(-0.5, 1.0, -0.45),
        Vec3::new(0.5, 1.6, 0.3),
        w as f32 / h as f32,
    );
    let mut pixels = render(ctx, &meshes, &camera, w, h).unwrap();
    draw_legend(&mut pixels, w, h, &strain_legend(0.2));
    let golden = common::fixture("golden/sheet_sphere_strain.png");
    if std::env::var_os("DRAPEKIT_BLESS").is_some() {
        drapekit::preview::write_png(&golden, &pixels, w, h).unwrap();
    }
    let want = image::open(&golden)
        .unwrap_or_else(|e| {
            panic!(
                "{}: {e}; render it with DRAPEKIT_BLESS=1 cargo test --release --test preview, \
                 look at it, and commit it",
                golden.display()
            )
        })
        .to_rgba8();
    assert_eq!((want.width(), want.height()), (w, h));
    // Lavapipe rasterises deterministically, but another Mesa/LLVM may round a lit colour by
    // a level or two and resolve a 2×2-supersampled edge sample the other way (one of four
    // samples: up to a quarter of the edge's contrast). So: every pixel within 3 levels, except
    // at most 1% of them (the silhouettes cover about 8% of this image); and none off by more
    // than half the range, which a missing mesh, a wrong colour map or a moved camera exceeds.
    let mut off = 0;
    let mut worst = 0;
    for (a, b) in pixels.chunks_exact(4).zip(want.as_raw().chunks_exact(4)) {
        let d = (0..3)
            .map(|c| (a[c] as i32 - b[c] as i32).abs())
            .max()
            .unwrap();
        worst = worst.max(d);
        off += (d > 3) as u32;
    }
    let allowed = w * h / 100;
    if off > allowed || worst > 128 {
        let diff = std::env::temp_dir().join("drapekit-golden-actual.png");
        drapekit::preview::write_png(&diff, &pixels, w, h).unwrap();
        panic!(
            "{off} pixels differ by more than 3 levels (allowed {allowed}), worst {worst}; \
             this render is in {}",
            diff.display()
        );
    }
}

#[test]
fn seam_lines_are_dark_thin_and_on_top() {
    let Some(ctx) = common::gpu() else { return };
    let white = Vec3::splat(0.8);
    let mesh = sheet(white);
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
    // The animation: every written frame (0, 3, …, 12), 96×72, each shown 3/24 s.
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
fn fabric_mode_colours_each_panel_and_lays_a_checker_over_the_pattern() {
    if common::gpu().is_none() {
        return;
    }
    // The sheet as two panels (left and right of x = 0) with pattern coordinates u = x + 0.5,
    // v = y − 1 in m, as drapekit writes garment frames.
    let m = sheet(Vec3::ONE);
    let mut text = String::new();
    for p in &m.positions {
        text += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    for p in &m.positions {
        text += &format!("vt {} {}\n", p.x + 0.5, p.y - 1.0);
    }
    for (name, left) in [("left", true), ("right", false)] {
        text += &format!("g {name}\n");
        for t in &m.triangles {
            let cx: f32 = t.iter().map(|&i| m.positions[i as usize].x).sum();
            if (cx < 0.0) == left {
                let [a, b, c] = t.map(|i| i + 1);
                text += &format!("f {a}/{a} {b}/{b} {c}/{c}\n");
            }
        }
    }
    let dir = std::env::temp_dir().join(format!("drapekit-panels-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("frame_0000.obj"), text).unwrap();
    let frame = drapekit::preview::read_obj(&dir.join("frame_0000.obj")).unwrap();
    assert_eq!(frame.uv.len(), m.positions.len());
    assert_eq!(*frame.groups.iter().max().unwrap(), 1);
    let mut previewer = Previewer::new(&dir, None, 24.0, &AdapterChoice::Fallback).unwrap();
    let (w, h) = (200u32, 150u32);
    let look = Look {
        camera: CameraChoice::Preset(CameraPreset::Front),
        mode: ColorMode::Fabric,
        size: (w, h),
        strain_max: 0.2,
        seams: false,
        legend: true,
        colors: Vec::new(),
        checker: 0.1,
    };
    let pixels = previewer.image(None, &look, None).unwrap();
    let camera = CameraPreset::Front.framing(
        Vec3::new(-0.5, 1.0, 0.0),
        Vec3::new(0.5, 1.6, 0.0),
        4.0 / 3.0,
    );
    let vp = camera.view_proj(w as f32 / h as f32);
    let at = |p: Vec3| {
        let c = vp * p.extend(1.0);
        let (x, y) = (
            ((c.x / c.w + 1.0) * 0.5 * w as f32) as u32,
            ((1.0 - c.y / c.w) * 0.5 * h as f32) as u32,
        );
        let k = 4 * (y * w + x) as usize;
        [pixels[k], pixels[k + 1], pixels[k + 2]]
    };
    // Centres of checker squares (0.1 m): (u, v) cells (1, 3) and (7, 3) are light, (2, 3)
    // dark (alternate squares are 30% darker); the panels take the palette's first two colours.
    let palette = drapekit::preview::PALETTE;
    for (x, color, shade) in [
        (-0.35, palette[0], 1.0),
        (-0.25, palette[0], 0.7),
        (0.25, palette[1], 1.0),
    ] {
        let got = at(Vec3::new(x, 1.35, 0.0));
        let want = (color * shade * facing_light()).to_array().map(srgb_byte);
        // As for the strain colours: the GPU's f32 lighting and sRGB rounding, 3 levels.
        for c in 0..3 {
            assert!(
                (got[c] as i32 - want[c] as i32).abs() <= 3,
                "x = {x}: rendered {got:?}, expected {want:?}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
