//! The armpit with the arms lowered: where the arm's inside and the torso's side are a
//! centimetre or two apart, inverse skinning must still map every point near the skin back to
//! the rest pose (some part claims it) and give its distance close to the exact deformed mesh's.

use drapekit::body::exact::ExactBody;
use drapekit::body::sdf::SDF_FAR;
use drapekit::cpu::deformed_sample;
use drapekit::mesh::TriMesh;
use drapekit::scene::Scene;
use drapekit::sim::{part_poses, prepare};

mod common;

#[test]
fn every_point_near_the_lowered_arms_armpit_is_claimed_and_near_its_exact_distance() {
    let dir = std::env::temp_dir().join(format!("drapekit-armpit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let body = common::Mannequin {
        animation: "arms-down",
        transition_s: 0.0,
        sdf_resolution_m: 0.005,
        friction: None,
    }
    .body_toml();
    let text = format!(
        r#"
[cloth.grid]
columns = 2
rows = 2
width_m = 0.1
height_m = 0.1
center_m = [0.0, 3.0, 0.0]

[fabric]
preset = "cotton"

{body}
[solver]
fps = 24
frames = 40
"#
    );
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    let prep = prepare(&Scene::load(&path).unwrap()).unwrap();
    let c = &prep.model.colliders[0];
    let d = &c.deformed.as_ref().unwrap().deformation;
    // Halfway down, and the arms-down motion's end (1.5 s) and after it (held).
    for t in [0.75f32, 1.5, 1.6] {
        let posed = d.positions_at(t);
        let tris = c.body.mesh.triangles.clone();
        let normals = drapekit::mesh::vertex_normals(&posed, &tris);
        let exact = ExactBody::new(&TriMesh {
            positions: posed.clone(),
            triangles: tris,
        })
        .unwrap();
        let parts = part_poses(&prep.model, t);
        let body = &prep.params.bodies[0];
        let (mut n, mut far, mut off1, mut inside_missed) = (0, 0, 0, 0);
        let mut worst = 0.0f32;
        for (p, nn) in posed.iter().zip(&normals) {
            // Both armpits: the arm's inside and the torso's side below the shoulder.
            if !(p.x.abs() > 0.08 && p.x.abs() < 0.26 && p.y > 1.08 && p.y < 1.36) {
                continue;
            }
            // From inside the skin to the shell where collision acts, both sides of the 3 mm
            // thickness.
            for depth in [-6e-3f32, -3e-3, -1e-3, 1e-3, 2e-3, 4e-3, 8e-3] {
                let x = *p + depth * *nn;
                let e = exact.query(x).0;
                if e.abs() > 0.012 {
                    continue;
                }
                n += 1;
                let s = deformed_sample(body, &parts, &c.sdf.values, x);
                if s.phi >= SDF_FAR * 0.5 {
                    far += 1;
                    if e < 0.003 {
                        inside_missed += 1;
                    }
                    continue;
                }
                let err = (s.phi - e).abs();
                worst = worst.max(err);
                if err > 1e-3 {
                    off1 += 1;
                }
            }
        }
        eprintln!(
            "t={t}: {n} points within 12 mm of the armpit surface; unclaimed {far} \
             ({inside_missed} of them within the thickness); off by >1 mm {off1}; \
             worst error {worst:.4} m"
        );
        assert!(n > 1000, "only {n} points probed");
        // No part claiming a point is what let cloth sink into the armpit.
        assert_eq!(
            far, 0,
            "{far} points unclaimed ({inside_missed} within the thickness)"
        );
        // A claimed point's distance is the rest SDF's (5 mm cells) through a blend of part
        // rotations that does not keep lengths near a joint. Under the 3 mm thickness, a
        // particle that collision holds at the thickness by this distance is outside the
        // exact deformed mesh; 2 mm leaves 1 mm of that. Measured: at most 1.6 mm, 14 of
        // 7,770 points over 1 mm.
        assert!(worst < 2e-3, "a distance is {worst} m off the exact one");
    }
}
