mod common;
use common::fixture;
use drapekit::cpu::CpuSolver;
use drapekit::model::layout::INTEGRATOR_IMPLICIT;
use drapekit::scene::Scene;
use drapekit::sim::{prepare, substep_params};
use drapekit::solver::Solver;

fn sheet(columns: u32, multigrid: bool, iterations: u32, stiffness: f32) -> Scene {
    let mut scene = Scene::load(&fixture("scenes/hanging_cloth.toml")).unwrap();
    scene.fabric.stretch_stiffness = stiffness;
    if let drapekit::scene::ClothSource::Grid {
        columns: c,
        rows: r,
        ..
    } = &mut scene.cloth
    {
        *c = columns;
        *r = columns;
    }
    scene.solver.integrator = INTEGRATOR_IMPLICIT;
    scene.solver.substeps = Some(1);
    scene.solver.iterations = iterations;
    scene.solver.multigrid = multigrid;
    scene.solver.tolerance = Some(1e-6);
    scene.solver.smoothing_sweeps = std::env::var("SMOOTH")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2);
    scene.solver.strain_limit = None;
    scene
}

#[test]
#[ignore]
fn probe_sheet() {
    let k: f32 = std::env::var("K")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3000.0);
    for columns in [17u32, 33, 65] {
        for mg in [false, true] {
            let iters: u32 = if mg {
                std::env::var("NEWTON")
                    .ok()
                    .and_then(|v| v.parse().ok())
                    .unwrap_or(4)
            } else {
                200
            };
            let scene = sheet(columns, mg, iters, k);
            let prep = prepare(&scene).unwrap();
            let sizes = prep.model.multigrid.as_ref().map(|m| m.sizes());
            let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
            let t = std::time::Instant::now();
            cpu.advance(&substep_params(&prep, 1)).unwrap();
            let el = t.elapsed().as_secs_f64();
            let v = cpu.vbd.as_ref().unwrap();
            let hist: Vec<String> = v
                .history
                .iter()
                .map(|(s, m, r)| format!("{s}:{m:.2e}/{r:.2e}"))
                .collect();
            let alphas = v.newton.as_ref().map(|c| c.alphas.clone());
            println!(
                "cols {columns} mg {mg} sizes {sizes:?} {el:.3}s\n  {}\n  alphas {alphas:?}",
                hist.join(" ")
            );
        }
    }
}

#[test]
#[ignore]
fn probe_shirt() {
    let frames: u32 = std::env::var("FRAMES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(30);
    let newton: u32 = std::env::var("NEWTON")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(6);
    let sub: u32 = std::env::var("SUB")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2);
    let mut scene = Scene::load(&fixture("scenes/tshirt_drape_cotton.toml")).unwrap();
    scene.solver.substeps = Some(sub);
    scene.solver.iterations = newton;
    scene.solver.tolerance = Some(1e-6);
    scene.solver.strain_limit = None;
    if std::env::var("NOFRICTION").is_ok() {
        for b in &mut scene.bodies {
            b.friction = 0.0;
        }
    }
    if std::env::var("NOBODY").is_ok() {
        scene.bodies.clear();
    }
    scene.solver.smoothing_sweeps = std::env::var("SMOOTH")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2);
    let prep = prepare(&scene).unwrap();
    println!(
        "sizes {:?}",
        prep.model.multigrid.as_ref().map(|m| m.sizes())
    );
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    cpu.vbd.as_mut().unwrap().profile = Some(Default::default());
    let mut stats = drapekit::sim::RunStats::default();
    let t = std::time::Instant::now();
    let mut prep2 = prep.clone();
    prep2.frames = frames;
    prep2.settle_speed = None;
    drapekit::sim::simulate(&prep2, &mut cpu, &mut stats, |f, _| {
        if f % 6 == 0 || f + 3 > frames {
            let v = cpu_hist();
            let _ = v;
        }
        Ok(())
    })
    .unwrap();
    let v = cpu.vbd.as_ref().unwrap();
    let prof = v.profile.as_ref().unwrap();
    let sweep_t = prof
        .get("vbd_solve")
        .map(|p| p.1 / p.0 as f64)
        .unwrap_or(1.0);
    for (k, (c, t)) in prof {
        println!(
            "  prof {k:18} n {c:8} total {t:7.3}s per {:8.1}us = {:.2} sweeps",
            t / *c as f64 * 1e6,
            t / *c as f64 / sweep_t
        );
    }
    let hist: Vec<String> = v
        .history
        .iter()
        .map(|(s, m, r)| format!("{s}:{m:.2e}/{r:.2e}"))
        .collect();
    println!(
        "frame {frames} {:.1}s strain {:.4} seams {:?}\n  {}\n  alphas {:?}",
        t.elapsed().as_secs_f64(),
        stats.last_edge_strain,
        stats.seams_closed_frame,
        hist.join(" "),
        v.newton.as_ref().map(|n| n.alphas.clone())
    );
}
fn cpu_hist() {}
thread_local! { static ERR: std::cell::RefCell<Vec<[f64;3]>> = std::cell::RefCell::new(Vec::new()); }

#[test]
#[ignore]
fn probe_shirt_worst() {
    use drapekit::plan::Pass;
    let frames: u32 = std::env::var("FRAMES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(40);
    let newton: u32 = std::env::var("NEWTON")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(6);
    let sub: u32 = std::env::var("SUB")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2);
    let mut scene = Scene::load(&fixture("scenes/tshirt_drape_cotton.toml")).unwrap();
    scene.solver.substeps = Some(sub);
    scene.solver.iterations = newton;
    scene.solver.tolerance = Some(1e-6);
    scene.solver.strain_limit = None;
    let mut prep = prepare(&scene).unwrap();
    prep.frames = frames;
    prep.settle_speed = None;
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut stats = drapekit::sim::RunStats::default();
    drapekit::sim::simulate(&prep, &mut cpu, &mut stats, |_, _| Ok(())).unwrap();
    let params = drapekit::sim::phase_params(&prep, frames, &stats);
    cpu.set_params(&params);
    let step = substep_params(&prep, frames + 1)[0];
    cpu.run_pass(Pass::VbdInit, &step);
    cpu.run_pass(Pass::VbdSolve, &step);
    let v = cpu.vbd.as_ref().unwrap();
    let el = drapekit::cpu::Elements::new(&prep.model);
    let view = el.view();
    let s = drapekit::cpu::Implicit {
        params: &params,
        step: &step,
        prev: &cpu.pos,
        target: &v.y,
        el: &view,
        planes: &v.planes,
        lambdas: &v.lambdas,
    };
    let g = 9.81;
    let mut worst: Vec<(f32, usize)> = (0..prep.model.len())
        .map(|i| (s.force_residual(i, &v.x, g), i))
        .collect();
    worst.sort_by(|a, b| b.0.partial_cmp(&a.0).unwrap());
    let hist: Vec<String> = v
        .history
        .iter()
        .map(|(s, m, r)| format!("{s}:{m:.2e}/{r:.2e}"))
        .collect();
    println!("{}", hist.join(" "));
    println!("alphas {:?}", v.newton.as_ref().map(|n| n.alphas.clone()));
    let n = prep.model.len();
    for &(r, i) in worst.iter().take(12) {
        let plane = v.planes[i];
        let phi = plane.w + plane.truncate().dot(v.x[i].truncate());
        let seams = prep
            .model
            .seams
            .iter()
            .filter(|sm| sm.v[..3].contains(&(i as u32)))
            .count();
        let sys = s.vertex_system(i, &v.x, None, &mut |_, _| {});
        println!(
            "  v{i} res {r:.3} phi {:.6} lambda {:.2e} seams {seams} |D| {:.2e} f {:?} n {:?} {}",
            phi,
            v.lambdas[i].x,
            v.x[i].truncate().length(),
            sys.force,
            plane.truncate(),
            prep.describe_particle(i as u32)
        );
    }
    let _ = n;
}

#[test]
#[ignore]
fn probe_shirt_linear() {
    use drapekit::plan::Pass;
    let frames: u32 = std::env::var("FRAMES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(40);
    for newton in 1..=4u32 {
        let mut scene = Scene::load(&fixture("scenes/tshirt_drape_cotton.toml")).unwrap();
        scene.solver.substeps = Some(2);
        scene.solver.iterations = 4;
        scene.solver.tolerance = Some(1e-6);
        scene.solver.strain_limit = None;
        let mut prep = prepare(&scene).unwrap();
        prep.frames = frames;
        prep.settle_speed = None;
        let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
        let mut stats = drapekit::sim::RunStats::default();
        drapekit::sim::simulate(&prep, &mut cpu, &mut stats, |_, _| Ok(())).unwrap();
        let mut params = drapekit::sim::phase_params(&prep, frames, &stats);
        params.iterations = newton;
        let mut solver = CpuSolver::new(&prep.model, params, &prep.plan);
        solver.set_state(&cpu.state().unwrap());
        let step = substep_params(&prep, frames + 1)[0];
        solver.run_pass(Pass::VbdInit, &step);
        solver.run_pass(Pass::VbdSolve, &step);
        let v = solver.vbd.as_ref().unwrap();
        let nt = v.newton.as_ref().unwrap();
        let norm = |a: &[glam::Vec4]| {
            a.iter()
                .map(|x| x.truncate().length_squared())
                .sum::<f32>()
                .sqrt()
        };
        println!(
            "newton {newton}: |f| {:.3e} |r_end| {:.3e} ratio {:.2e} alphas {:?} hist {:?}",
            norm(&nt.force),
            norm(&nt.levels[0].rhs),
            norm(&nt.levels[0].rhs) / norm(&nt.force),
            nt.alphas,
            v.history.last()
        );
    }
}

#[test]
#[ignore]
fn probe_symmetry() {
    use drapekit::plan::Pass;
    let frames: u32 = std::env::var("FRAMES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(40);
    let mut scene = Scene::load(&fixture("scenes/tshirt_drape_cotton.toml")).unwrap();
    scene.solver.substeps = Some(2);
    scene.solver.iterations = 2;
    scene.solver.strain_limit = None;
    if std::env::var("NOBODY").is_ok() {
        scene.bodies.clear();
    }
    if std::env::var("NOBEND").is_ok() {
        scene.fabric.bending_stiffness = None;
    }
    let mut prep = prepare(&scene).unwrap();
    prep.frames = frames;
    prep.settle_speed = None;
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut stats = drapekit::sim::RunStats::default();
    drapekit::sim::simulate(&prep, &mut cpu, &mut stats, |_, _| Ok(())).unwrap();
    let step = substep_params(&prep, frames + 1)[0];
    cpu.run_pass(Pass::VbdInit, &step);
    cpu.run_pass(Pass::VbdSolve, &step);
    let v = cpu.vbd.as_ref().unwrap();
    let nt = v.newton.as_ref().unwrap();
    let mg = &nt.structure;
    let h = &nt.levels[0].blocks;
    let mut worst = (0.0f32, 0usize, 0usize, 0.0f32);
    for i in 0..mg.fine.rows() {
        for b in mg.fine.offsets[i]..mg.fine.offsets[i + 1] {
            let j = mg.fine.columns[b as usize] as usize;
            let bt = mg.fine.find(j as u32, i as u32).unwrap();
            let a = h[b as usize];
            let c = h[bt as usize].transpose();
            let d = (a - c)
                .abs()
                .to_cols_array()
                .iter()
                .cloned()
                .fold(0.0, f32::max);
            let sc = a.abs().to_cols_array().iter().cloned().fold(0.0, f32::max);
            if d > worst.0 {
                worst = (d, i, j, sc);
            }
        }
    }
    println!("worst asym {:?}", worst);
    {
        use drapekit::cpu::*;
        use glam::{Mat3, Vec4};
        let h0 = h.clone();
        let mut lv: Vec<Vec<Mat3>> = Vec::new();
        for (k, l) in mg.levels.iter().enumerate() {
            let finer = if k == 0 { &h0 } else { &lv[k - 1] };
            let mut out = vec![Mat3::ZERO; l.pattern.blocks()];
            coarse_operator(&l.galerkin, finer, &mut out);
            lv.push(out);
        }
        let col = prep.model.vertex_coloring();
        let hi = Hier {
            mg: mg.clone(),
            fine_order: col.order.clone(),
            fine_offsets: col.offsets.clone(),
            h: h0.clone(),
            lv,
            pinned: (0..prep.model.len()).map(|i| cpu.pos[i].w == 0.0).collect(),
        };
        let f = nt.force.clone();
        let n = f.len();
        let dotf = |a: &[Vec4], b: &[Vec4]| {
            a.iter()
                .zip(b)
                .map(|(x, y)| (x.truncate().dot(y.truncate())) as f64)
                .sum::<f64>()
        };
        let mut x = vec![Vec4::ZERO; n];
        let mut r = f.clone();
        let r0 = dotf(&r, &r).sqrt();
        let nu: usize = std::env::var("NU")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(1);
        let cs: usize = std::env::var("CS")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(30);
        let centre =
            cpu.pos.iter().map(|p| p.truncate()).sum::<glam::Vec3>() / cpu.pos.len() as f32;
        let xs: Vec<glam::Vec3> = (0..n)
            .map(|i| cpu.pos[i].truncate() + v.x[i].truncate() - centre)
            .collect();
        let six = std::env::var("SIX").is_ok();
        let hi6 = Hier6 {
            mg: mg.clone(),
            fine_order: col.order.clone(),
            fine_offsets: col.offsets.clone(),
            h: h0.clone(),
            lv: build6(&mg, &h0, &xs),
            pinned: hi.pinned.clone(),
            x: xs.clone(),
        };
        let pre = |r: &[Vec4]| {
            if six {
                vcycle6(&hi6, r, nu, cs)
            } else {
                vcycle(&hi, r, nu, cs)
            }
        };
        let mut z = pre(&r);
        let mut p = z.clone();
        let mut rz = dotf(&r, &z);
        let mut ap = vec![Vec4::ZERO; n];
        for it in 0..40 {
            level_residual(&mg.fine, &h0, &vec![Vec4::ZERO; n], &p, &mut ap);
            for a in ap.iter_mut() {
                *a = -*a;
            }
            let alpha = rz / dotf(&p, &ap);
            for i in 0..n {
                x[i] += alpha as f32 * p[i];
                r[i] -= alpha as f32 * ap[i];
            }
            let mut tr = vec![Vec4::ZERO; n];
            level_residual(&mg.fine, &h0, &f, &x, &mut tr);
            if it % 4 == 3 {
                println!(
                    "mg-pcg32 {it}: rec {:.3e} true {:.3e}",
                    dotf(&r, &r).sqrt() / r0,
                    dotf(&tr, &tr).sqrt() / r0
                );
            }
            if it == 39 && std::env::var("EXACT").is_ok() {
                let xs32: Vec<[f64; 3]> = x
                    .iter()
                    .map(|v| [v.x as f64, v.y as f64, v.z as f64])
                    .collect();
                ERR.with(|e| *e.borrow_mut() = xs32);
            }
            z = pre(&r);
            let rz2 = dotf(&r, &z);
            let be = rz2 / rz;
            rz = rz2;
            for i in 0..n {
                p[i] = z[i] + be as f32 * p[i];
            }
        }
    }
    // f64 Jacobi-PCG on H c = f
    let n = mg.fine.rows();
    let f: Vec<[f64; 3]> = nt
        .force
        .iter()
        .map(|x| [x.x as f64, x.y as f64, x.z as f64])
        .collect();
    let mv = |x: &Vec<[f64; 3]>| -> Vec<[f64; 3]> {
        (0..n)
            .map(|i| {
                let mut s = [0.0; 3];
                for b in mg.fine.offsets[i]..mg.fine.offsets[i + 1] {
                    let j = mg.fine.columns[b as usize] as usize;
                    let m = h[b as usize].to_cols_array();
                    for r in 0..3 {
                        for c in 0..3 {
                            s[r] += m[c * 3 + r] as f64 * x[j][c];
                        }
                    }
                }
                s
            })
            .collect()
    };
    let dinv: Vec<glam::DMat3> = (0..n)
        .map(|i| {
            let m = h[mg.fine.offsets[i] as usize].as_dmat3();
            if m.determinant().abs() > 1e-30 {
                m.inverse()
            } else {
                glam::DMat3::ZERO
            }
        })
        .collect();
    let prec = |r: &Vec<[f64; 3]>| -> Vec<[f64; 3]> {
        (0..n)
            .map(|i| (dinv[i] * glam::DVec3::from(r[i])).into())
            .collect()
    };
    let dot = |a: &Vec<[f64; 3]>, b: &Vec<[f64; 3]>| {
        a.iter()
            .zip(b)
            .map(|(x, y)| x[0] * y[0] + x[1] * y[1] + x[2] * y[2])
            .sum::<f64>()
    };
    let mut x = vec![[0.0; 3]; n];
    let mut r = f.clone();
    let mut z = prec(&r);
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let r0 = dot(&r, &r).sqrt();
    let its = if std::env::var("EXACT").is_ok() {
        4000
    } else {
        0
    };
    for it in 0..its {
        if it == its - 1 {
            let mgx = ERR.with(|e| e.borrow().clone());
            if !mgx.is_empty() {
                let mut errs: Vec<(f64, usize)> = (0..n)
                    .map(|i| {
                        (
                            ((x[i][0] - mgx[i][0]).powi(2)
                                + (x[i][1] - mgx[i][1]).powi(2)
                                + (x[i][2] - mgx[i][2]).powi(2))
                            .sqrt(),
                            i,
                        )
                    })
                    .collect();
                let tot: f64 = errs.iter().map(|e| e.0 * e.0).sum::<f64>().sqrt();
                let sol: f64 = x
                    .iter()
                    .map(|v| v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
                    .sum::<f64>()
                    .sqrt();
                errs.sort_by(|a, b| b.0.partial_cmp(&a.0).unwrap());
                println!("error norm {tot:.3e} of solution {sol:.3e}");
                let mut per_panel = std::collections::BTreeMap::new();
                for &(e, i) in &errs {
                    let d = prep.describe_particle(i as u32);
                    let panel = d.split('\'').nth(1).unwrap_or("?").to_string();
                    *per_panel.entry(panel).or_insert(0.0) += e * e;
                }
                println!("per panel {:?}", per_panel);
                for &(e, i) in errs.iter().take(8) {
                    println!("  err {e:.3e} {}", prep.describe_particle(i as u32));
                }
            }
        }
        let ap = mv(&p);
        let a = rz / dot(&p, &ap);
        for i in 0..n {
            for k in 0..3 {
                x[i][k] += a * p[i][k];
                r[i][k] -= a * ap[i][k];
            }
        }
        if it % 300 == 0 {
            println!("jacobi-pcg64 {it}: {:.3e}", dot(&r, &r).sqrt() / r0);
        }
        z = prec(&r);
        let rz2 = dot(&r, &z);
        let be = rz2 / rz;
        rz = rz2;
        for i in 0..n {
            for k in 0..3 {
                p[i][k] = z[i][k] + be * p[i][k];
            }
        }
    }
}

struct Hier {
    mg: std::sync::Arc<drapekit::model::multigrid::Multigrid>,
    fine_order: Vec<u32>,
    fine_offsets: Vec<u32>,
    h: Vec<glam::Mat3>,
    lv: Vec<Vec<glam::Mat3>>,
    pinned: Vec<bool>,
}

fn sweep(
    p: &drapekit::model::multigrid::BlockPattern,
    a: &[glam::Mat3],
    order: &[u32],
    offs: &[u32],
    rhs: &[glam::Vec4],
    e: &mut [glam::Vec4],
    back: bool,
) {
    let nc = offs.len() - 1;
    let cols: Vec<usize> = if back {
        (0..nc).rev().collect()
    } else {
        (0..nc).collect()
    };
    for c in cols {
        drapekit::cpu::smooth(p, a, &order[offs[c] as usize..offs[c + 1] as usize], rhs, e);
    }
}

fn vcycle(hi: &Hier, r: &[glam::Vec4], nu: usize, cs: usize) -> Vec<glam::Vec4> {
    use drapekit::cpu::*;
    use glam::Vec4;
    let mg = &hi.mg;
    let n = r.len();
    let mut z = vec![Vec4::ZERO; n];
    for _ in 0..nu {
        sweep(
            &mg.fine,
            &hi.h,
            &hi.fine_order,
            &hi.fine_offsets,
            r,
            &mut z,
            false,
        );
    }
    let mut res = vec![Vec4::ZERO; n];
    level_residual(&mg.fine, &hi.h, r, &z, &mut res);
    let m: usize = std::env::var("LEVELS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(mg.levels.len());
    let mut rhs: Vec<Vec<Vec4>> = mg
        .levels
        .iter()
        .map(|l| vec![Vec4::ZERO; l.len()])
        .collect();
    let mut e = rhs.clone();
    let mut rr = rhs.clone();
    restrict(&mg.levels[0].children, &res, &mut rhs[0], &mut e[0]);
    for k in 0..m - 1 {
        let l = &mg.levels[k];
        for _ in 0..nu {
            sweep(
                &l.pattern,
                &hi.lv[k],
                &l.order,
                &l.color_offsets,
                &rhs[k],
                &mut e[k],
                false,
            );
        }
        level_residual(&l.pattern, &hi.lv[k], &rhs[k], &e[k], &mut rr[k]);
        let (_a, b) = rhs.split_at_mut(k + 1);
        let (_ea, eb) = e.split_at_mut(k + 1);
        restrict(&mg.levels[k + 1].children, &rr[k], &mut b[0], &mut eb[0]);
    }
    let l = &mg.levels[m - 1];
    for _ in 0..cs {
        sweep(
            &l.pattern,
            &hi.lv[m - 1],
            &l.order,
            &l.color_offsets,
            &rhs[m - 1],
            &mut e[m - 1],
            false,
        );
        sweep(
            &l.pattern,
            &hi.lv[m - 1],
            &l.order,
            &l.color_offsets,
            &rhs[m - 1],
            &mut e[m - 1],
            true,
        );
    }
    for k in (0..m - 1).rev() {
        let (a, b) = e.split_at_mut(k + 1);
        prolong(
            &mg.levels[k + 1].parents,
            &mg.levels[k + 1].weights,
            &b[0],
            &mut a[k],
        );
        let l = &mg.levels[k];
        for _ in 0..nu {
            sweep(
                &l.pattern,
                &hi.lv[k],
                &l.order,
                &l.color_offsets,
                &rhs[k],
                &mut e[k],
                true,
            );
        }
    }
    let mut corr = vec![Vec4::ZERO; n];
    prolong(
        &mg.levels[0].parents,
        &mg.levels[0].weights,
        &e[0],
        &mut corr,
    );
    for i in 0..n {
        if !hi.pinned[i] {
            z[i] += corr[i];
        }
    }
    for _ in 0..nu {
        sweep(
            &mg.fine,
            &hi.h,
            &hi.fine_order,
            &hi.fine_offsets,
            r,
            &mut z,
            true,
        );
    }
    z
}

type M6 = [f32; 36];
type V6 = [f32; 6];
fn m6_mul_v(a: &M6, x: &V6) -> V6 {
    let mut o = [0.0; 6];
    for r in 0..6 {
        for c in 0..6 {
            o[r] += a[r * 6 + c] * x[c];
        }
    }
    o
}
fn solve6(a: &M6, b: &V6) -> V6 {
    // Cholesky with a pivot floor
    let mut l = [0.0f64; 36];
    let maxd = (0..6).map(|k| a[k * 6 + k] as f64).fold(0.0, f64::max);
    let mut skip = [false; 6];
    for j in 0..6 {
        let mut d = a[j * 6 + j] as f64;
        for k in 0..j {
            d -= l[j * 6 + k] * l[j * 6 + k];
        }
        if d <= 1e-7 * maxd {
            skip[j] = true;
            l[j * 6 + j] = 1.0;
            for i in j + 1..6 {
                l[i * 6 + j] = 0.0;
            }
            continue;
        }
        let dj = d.sqrt();
        l[j * 6 + j] = dj;
        for i in j + 1..6 {
            let mut s = a[i * 6 + j] as f64;
            for k in 0..j {
                s -= l[i * 6 + k] * l[j * 6 + k];
            }
            l[i * 6 + j] = s / dj;
        }
    }
    let mut y = [0.0f64; 6];
    for i in 0..6 {
        if skip[i] {
            y[i] = 0.0;
            continue;
        }
        let mut s = b[i] as f64;
        for k in 0..i {
            s -= l[i * 6 + k] * y[k];
        }
        y[i] = s / l[i * 6 + i];
    }
    let mut x = [0.0f64; 6];
    for i in (0..6).rev() {
        if skip[i] {
            x[i] = 0.0;
            continue;
        }
        let mut s = y[i];
        for k in i + 1..6 {
            s -= l[k * 6 + i] * x[k];
        }
        x[i] = s / l[i * 6 + i];
    }
    let mut o = [0.0f32; 6];
    for i in 0..6 {
        o[i] = x[i] as f32;
    }
    o
}
fn cross_m(x: glam::Vec3) -> glam::Mat3 {
    glam::Mat3::from_cols(
        glam::Vec3::new(0.0, x.z, -x.y),
        glam::Vec3::new(-x.z, 0.0, x.x),
        glam::Vec3::new(x.y, -x.x, 0.0),
    )
}
fn lift(h: glam::Mat3, xi: glam::Vec3, xj: glam::Vec3) -> M6 {
    // [[H, -H[xj]x],[[xi]x H, -[xi]x H [xj]x]]
    let cj = cross_m(xj);
    let ci = cross_m(xi);
    let b01 = -(h * cj);
    let b10 = ci * h;
    let b11 = -(ci * h * cj);
    let mut o = [0.0; 36];
    for r in 0..3 {
        for c in 0..3 {
            o[r * 6 + c] = h.col(c)[r];
            o[r * 6 + 3 + c] = b01.col(c)[r];
            o[(3 + r) * 6 + c] = b10.col(c)[r];
            o[(3 + r) * 6 + 3 + c] = b11.col(c)[r];
        }
    }
    o
}

struct Hier6 {
    mg: std::sync::Arc<drapekit::model::multigrid::Multigrid>,
    fine_order: Vec<u32>,
    fine_offsets: Vec<u32>,
    h: Vec<glam::Mat3>,
    lv: Vec<Vec<M6>>,
    pinned: Vec<bool>,
    x: Vec<glam::Vec3>,
}

fn build6(
    mg: &std::sync::Arc<drapekit::model::multigrid::Multigrid>,
    h: &[glam::Mat3],
    x: &[glam::Vec3],
) -> Vec<Vec<M6>> {
    let rows = mg.fine.rows();
    let mut g: Vec<M6> = vec![[0.0; 36]; mg.fine.blocks()];
    for i in 0..rows {
        for b in mg.fine.offsets[i]..mg.fine.offsets[i + 1] {
            let j = mg.fine.columns[b as usize] as usize;
            g[b as usize] = lift(h[b as usize], x[i], x[j]);
        }
    }
    let mut lv: Vec<Vec<M6>> = Vec::new();
    for (k, l) in mg.levels.iter().enumerate() {
        let finer = if k == 0 { &g } else { &lv[k - 1] };
        let mut out = vec![[0.0f32; 36]; l.pattern.blocks()];
        for c in 0..l.pattern.blocks() {
            for t in l.galerkin.offsets[c]..l.galerkin.offsets[c + 1] {
                let (f, w) = l.galerkin.items[t as usize];
                for q in 0..36 {
                    out[c][q] += w * finer[f as usize][q];
                }
            }
        }
        lv.push(out);
    }
    lv
}

fn gs6(
    p: &drapekit::model::multigrid::BlockPattern,
    a: &[M6],
    order: &[u32],
    offs: &[u32],
    rhs: &[V6],
    e: &mut [V6],
    back: bool,
) {
    let nc = offs.len() - 1;
    let cols: Vec<usize> = if back {
        (0..nc).rev().collect()
    } else {
        (0..nc).collect()
    };
    for c in cols {
        for &r in &order[offs[c] as usize..offs[c + 1] as usize] {
            let r = r as usize;
            let mut s = rhs[r];
            for b in p.offsets[r] + 1..p.offsets[r + 1] {
                let v = m6_mul_v(&a[b as usize], &e[p.columns[b as usize] as usize]);
                for q in 0..6 {
                    s[q] -= v[q];
                }
            }
            e[r] = solve6(&a[p.offsets[r] as usize], &s);
        }
    }
}
fn res6(p: &drapekit::model::multigrid::BlockPattern, a: &[M6], rhs: &[V6], e: &[V6]) -> Vec<V6> {
    (0..p.rows())
        .map(|r| {
            let mut s = rhs[r];
            for b in p.offsets[r]..p.offsets[r + 1] {
                let v = m6_mul_v(&a[b as usize], &e[p.columns[b as usize] as usize]);
                for q in 0..6 {
                    s[q] -= v[q];
                }
            }
            s
        })
        .collect()
}

fn vcycle6(hi: &Hier6, r: &[glam::Vec4], nu: usize, cs: usize) -> Vec<glam::Vec4> {
    use drapekit::cpu::*;
    use glam::Vec4;
    let mg = &hi.mg;
    let n = r.len();
    let mut z = vec![Vec4::ZERO; n];
    for _ in 0..nu {
        sweep(
            &mg.fine,
            &hi.h,
            &hi.fine_order,
            &hi.fine_offsets,
            r,
            &mut z,
            false,
        );
    }
    let mut res = vec![Vec4::ZERO; n];
    level_residual(&mg.fine, &hi.h, r, &z, &mut res);
    let m: usize = std::env::var("LEVELS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(mg.levels.len());
    let mut rhs: Vec<Vec<V6>> = mg.levels.iter().map(|l| vec![[0.0; 6]; l.len()]).collect();
    let mut e = rhs.clone();
    // restrict level 0 -> 1 with lifting
    let l1 = &mg.levels[0];
    for c in 0..l1.len() {
        let mut s = [0.0f32; 6];
        for t in l1.children.offsets[c]..l1.children.offsets[c + 1] {
            let (f, w) = l1.children.items[t as usize];
            let rv = res[f as usize].truncate();
            let tq = hi.x[f as usize].cross(rv);
            let v = [rv.x, rv.y, rv.z, tq.x, tq.y, tq.z];
            for q in 0..6 {
                s[q] += w * v[q];
            }
        }
        rhs[0][c] = s;
    }
    for k in 0..m - 1 {
        let l = &mg.levels[k];
        for _ in 0..nu {
            gs6(
                &l.pattern,
                &hi.lv[k],
                &l.order,
                &l.color_offsets,
                &rhs[k].clone(),
                &mut e[k],
                false,
            );
        }
        let rr = res6(&l.pattern, &hi.lv[k], &rhs[k], &e[k]);
        let lc = &mg.levels[k + 1];
        for c in 0..lc.len() {
            let mut s = [0.0f32; 6];
            for t in lc.children.offsets[c]..lc.children.offsets[c + 1] {
                let (f, w) = lc.children.items[t as usize];
                for q in 0..6 {
                    s[q] += w * rr[f as usize][q];
                }
            }
            rhs[k + 1][c] = s;
            e[k + 1][c] = [0.0; 6];
        }
    }
    let l = &mg.levels[m - 1];
    for _ in 0..cs {
        let rh = rhs[m - 1].clone();
        gs6(
            &l.pattern,
            &hi.lv[m - 1],
            &l.order,
            &l.color_offsets,
            &rh,
            &mut e[m - 1],
            false,
        );
        gs6(
            &l.pattern,
            &hi.lv[m - 1],
            &l.order,
            &l.color_offsets,
            &rh,
            &mut e[m - 1],
            true,
        );
    }
    for k in (0..m - 1).rev() {
        let lc = &mg.levels[k + 1];
        for i in 0..mg.levels[k].len() {
            for q in 0..3 {
                let (pp, ww) = (lc.parents[i][q], lc.weights[i][q]);
                for d in 0..6 {
                    e[k][i][d] += ww * e[k + 1][pp as usize][d];
                }
            }
        }
        let l = &mg.levels[k];
        let rh = rhs[k].clone();
        for _ in 0..nu {
            gs6(
                &l.pattern,
                &hi.lv[k],
                &l.order,
                &l.color_offsets,
                &rh,
                &mut e[k],
                true,
            );
        }
    }
    for i in 0..n {
        if hi.pinned[i] {
            continue;
        }
        let mut xi = [0.0f32; 6];
        for q in 0..3 {
            let (pp, ww) = (l1.parents[i][q], l1.weights[i][q]);
            for d in 0..6 {
                xi[d] += ww * e[0][pp as usize][d];
            }
        }
        let t = glam::Vec3::new(xi[0], xi[1], xi[2]);
        let th = glam::Vec3::new(xi[3], xi[4], xi[5]);
        z[i] += (t + th.cross(hi.x[i])).extend(0.0);
    }
    for _ in 0..nu {
        sweep(
            &mg.fine,
            &hi.h,
            &hi.fine_order,
            &hi.fine_offsets,
            r,
            &mut z,
            true,
        );
    }
    z
}

#[test]
#[ignore]
fn probe_gradient() {
    use drapekit::plan::Pass;
    let frames: u32 = std::env::var("FRAMES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(40);
    let mut scene = Scene::load(&fixture("scenes/tshirt_drape_cotton.toml")).unwrap();
    scene.solver.substeps = Some(2);
    scene.solver.iterations = 2;
    scene.solver.strain_limit = None;
    let mut prep = prepare(&scene).unwrap();
    prep.frames = frames;
    prep.settle_speed = None;
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut stats = drapekit::sim::RunStats::default();
    drapekit::sim::simulate(&prep, &mut cpu, &mut stats, |_, _| Ok(())).unwrap();
    let mut params = drapekit::sim::phase_params(&prep, frames, &stats);
    if std::env::var("NOFRICTION").is_ok() {
        params.bodies[0].friction = 0.0;
    }
    if std::env::var("NOBODYP").is_ok() {
        params.num_bodies = 0;
    }
    cpu.set_params(&params);
    let step = substep_params(&prep, frames + 1)[0];
    cpu.run_pass(Pass::VbdInit, &step);
    cpu.run_pass(Pass::VbdSolve, &step);
    let v = cpu.vbd.as_ref().unwrap();
    let el = drapekit::cpu::Elements::new(&prep.model);
    let view = el.view();
    let s = drapekit::cpu::Implicit {
        params: &params,
        step: &step,
        prev: &cpu.pos,
        target: &v.y,
        el: &view,
        planes: &v.planes,
        lambdas: &v.lambdas,
    };
    let n = prep.model.len();
    let mut rng = common::Rng::new(7);
    // per-term check: correction on one vertex at a time, group by kind
    let mut worst = (0.0f64, 0usize);
    let mut tot_err = 0.0f64;
    let mut tot = 0.0f64;
    for trial in 0..400 {
        let i = (trial * 6151) % n;
        if cpu.pos[i].w == 0.0 {
            continue;
        }
        let mut c = vec![glam::Vec4::ZERO; n];
        let mag: f32 = std::env::var("MAG")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(1e-5);
        c[i] = rng.vec3(mag).extend(0.0);
        let f = s.vertex_system(i, &v.x, None, &mut |_, _| {}).force;
        // energy change from all vertices that could own elements touching i: sum over all (cheap enough? n=2468 * 400)
        let a = [1.0f32, 0.5, 0.25];
        let mut dg = [0.0f64; 3];
        for k in 0..n {
            let e = s.energy_change(k, &v.x, &c, a);
            for q in 0..3 {
                dg[q] += e[q] as f64;
            }
        }
        let lin = -(f.dot(c[i].truncate())) as f64;
        // Richardson: dg(a) = lin*a + q a^2 ; estimate derivative from a=0.5,0.25: d = (4*dg(.25) - dg(.5))/(0.5)
        let deriv = (4.0 * dg[2] - dg[1]) / 0.5;
        let err = (deriv - lin).abs();
        tot_err += err;
        tot += lin.abs();
        if err / lin.abs().max(1e-30) > worst.0 && lin.abs() > 1e-12 {
            worst = (err / lin.abs(), i);
        }
    }
    for &(k, label) in &[(0usize, "none")] {
        let _ = (k, label);
    }
    println!(
        "relative gradient error: total {:.3e}, worst {:.3e} at {}",
        tot_err / tot,
        worst.0,
        prep.describe_particle(worst.1 as u32)
    );
}

fn shirt_state(
    frames: u32,
) -> (
    drapekit::sim::Prepared,
    drapekit::solver::ParticleState,
    drapekit::sim::RunStats,
) {
    let path = format!("/tmp/shirt_state_{frames}.json");
    let mut scene = Scene::load(&fixture("scenes/tshirt_drape_cotton.toml")).unwrap();
    scene.solver.multigrid = false;
    scene.solver.iterations = 3;
    scene.solver.substeps = Some(8);
    let mut prep = prepare(&scene).unwrap();
    prep.frames = frames;
    prep.settle_speed = None;
    if let Ok(text) = std::fs::read_to_string(&path) {
        let (p, v, closed): (Vec<[f32; 4]>, Vec<[f32; 4]>, Option<u32>) =
            serde_json::from_str(&text).unwrap();
        let mut stats = drapekit::sim::RunStats::default();
        stats.seams_closed_frame = closed;
        return (
            prep,
            drapekit::solver::ParticleState {
                positions: p.into_iter().map(glam::Vec4::from).collect(),
                velocities: v.into_iter().map(glam::Vec4::from).collect(),
            },
            stats,
        );
    }
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut stats = drapekit::sim::RunStats::default();
    drapekit::sim::simulate(&prep, &mut cpu, &mut stats, |_, _| Ok(())).unwrap();
    let st = cpu.state().unwrap();
    let p: Vec<[f32; 4]> = st.positions.iter().map(|v| v.to_array()).collect();
    let v: Vec<[f32; 4]> = st.velocities.iter().map(|v| v.to_array()).collect();
    std::fs::write(
        &path,
        serde_json::to_string(&(p, v, stats.seams_closed_frame)).unwrap(),
    )
    .unwrap();
    (prep, st, stats)
}

#[test]
#[ignore]
fn probe_bench() {
    use drapekit::plan::Pass;
    let frames: u32 = std::env::var("FRAMES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(120);
    let sub: u32 = std::env::var("SUB")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(8);
    let (prep0, state, stats) = shirt_state(frames);
    let mut scene = Scene::load(&fixture("scenes/tshirt_drape_cotton.toml")).unwrap();
    if std::env::var("NOBEND").is_ok() {
        scene.fabric.bending_stiffness = None;
    }
    scene.solver.substeps = Some(sub);
    scene.solver.strain_limit = None;
    scene.solver.tolerance = Some(1e-9);
    let configs: Vec<(bool, u32)> = vec![
        (false, 1),
        (false, 3),
        (false, 10),
        (false, 30),
        (false, 100),
        (false, 300),
        (true, 1),
        (true, 2),
        (true, 4),
        (true, 8),
        (true, 12),
        (true, 16),
        (true, 24),
    ];
    let mut sweep_t = 0.0;
    for (mg, iters) in configs {
        scene.solver.multigrid = mg;
        scene.solver.iterations = iters;
        let prep = prepare(&scene).unwrap();
        let mut params = drapekit::sim::phase_params(&prep, frames, &stats);
        params.gravity = prep0.params.gravity;
        params.gravity = prep.gravity.0.extend(0.0).to_array();
        if std::env::var("NOFRICTION").is_ok() {
            params.bodies[0].friction = 0.0;
        }
        if std::env::var("NOCONTACT").is_ok() {
            params.num_bodies = 0;
        }
        let mut cpu = CpuSolver::new(&prep.model, params, &prep.plan);
        cpu.vbd.as_mut().unwrap().profile = Some(Default::default());
        cpu.set_state(&state);
        let step = substep_params(&prep, frames + 1)[0];
        cpu.run_pass(Pass::VbdInit, &step);
        let t = std::time::Instant::now();
        cpu.run_pass(Pass::VbdSolve, &step);
        let el = t.elapsed().as_secs_f64();
        let v = cpu.vbd.as_ref().unwrap();
        let prof = v.profile.as_ref().unwrap();
        if !mg {
            sweep_t = prof.get("vbd_solve").map(|p| p.1 / p.0 as f64).unwrap();
        }
        let fr = prof.get("force_residual").map(|p| p.1).unwrap_or(0.0);
        let cost = (el - fr) / sweep_t;
        let last = v.history.last().unwrap();
        println!(
            "mg {mg} iters {iters:4}: cost {cost:7.1} sweeps, residual max {:.3e} rms {:.3e}",
            last.1, last.2
        );
    }
}

#[test]
#[ignore]
fn probe_fine_worst() {
    // 2 cm shirt (new solver) to frame 60, mapped to 5 mm; one substep: sweeps then Newton, worst vertices
    use drapekit::plan::{newton_correction, Pass, SolveOp, SolveShape};
    let div: f64 = std::env::var("DIV")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(4.0);
    let mut scene = Scene::load(&fixture("scenes/tshirt_drape_cotton.toml")).unwrap();
    scene.solver.iterations = 1;
    let mut prep = prepare(&scene).unwrap();
    prep.frames = 60;
    prep.settle_speed = None;
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut stats = drapekit::sim::RunStats::default();
    drapekit::sim::simulate(&prep, &mut cpu, &mut stats, |_, _| Ok(())).unwrap();
    let state = cpu.state().unwrap();
    let mut fine = scene.clone();
    if let drapekit::scene::ClothSource::Pattern { options, .. } = &mut fine.cloth {
        options.particle_distance /= div;
    }
    let fp = prepare(&fine).unwrap();
    println!(
        "levels {:?}",
        fp.model.multigrid.as_ref().map(|m| m.sizes())
    );
    let tr = drapekit::pattern::transfer::Transfer::new(
        prep.garment.as_ref().unwrap(),
        fp.garment.as_ref().unwrap(),
    );
    let pos = tr.apply(&state.positions);
    let vel = tr.apply(&state.velocities);
    let packed = fp.model.packed_positions();
    let st = drapekit::solver::ParticleState {
        positions: pos
            .iter()
            .zip(&packed)
            .map(|(p, q)| p.extend(q.w))
            .collect(),
        velocities: vel.iter().map(|v| v.extend(0.0)).collect(),
    };
    let params = drapekit::sim::phase_params(&fp, 60, &stats);
    let mut s2 = CpuSolver::new(&fp.model, params, &fp.plan);
    s2.set_state(&st);
    let relax: u32 = std::env::var("RELAX")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2);
    for f in 61..61 + relax {
        s2.advance(&substep_params(&fp, f)).unwrap();
    }
    let step = substep_params(&fp, 61 + relax)[0];
    s2.run_pass(Pass::VbdInit, &step);
    s2.run_solve_ops(&[SolveOp::ContactPlanes], &step);
    let shape = SolveShape::for_run(&fp.model, &params, &fp.plan);
    let report = |s2: &CpuSolver, label: &str| {
        let v = s2.vbd.as_ref().unwrap();
        let el = drapekit::cpu::Elements::new(&fp.model);
        let view = el.view();
        let s = drapekit::cpu::Implicit {
            params: &params,
            step: &step,
            prev: &s2.pos,
            target: &v.y,
            el: &view,
            planes: &v.planes,
            lambdas: &v.lambdas,
        };
        let mut worst: Vec<(f32, usize)> = (0..fp.model.len())
            .map(|i| (s.force_residual(i, &v.x, 9.81), i))
            .collect();
        let rms =
            (worst.iter().map(|w| (w.0 * w.0) as f64).sum::<f64>() / worst.len() as f64).sqrt();
        worst.sort_by(|a, b| b.0.partial_cmp(&a.0).unwrap());
        println!("{label}: rms {rms:.3e}");
        for &(r, i) in worst.iter().take(6) {
            let plane = v.planes[i];
            let phi = plane.w + plane.truncate().dot(v.x[i].truncate());
            let sys = s.vertex_system(i, &v.x, None, &mut |_, _| {});
            println!(
                "  v{i} res {r:.1} phi {:.6} lambda {:.2e} |D| {:.2e} |f| {:.2e} {}",
                phi,
                v.lambdas[i].x,
                v.x[i].truncate().length(),
                sys.force.length(),
                fp.describe_particle(i as u32)
            );
        }
    };
    report(&s2, "start");
    s2.run_solve_ops(&vec![SolveOp::Sweep { iteration: 0 }; 8], &step);
    report(&s2, "8 sweeps");
    for k in 0..3 {
        s2.run_solve_ops(&newton_correction(shape), &step);
        let nt = s2.vbd.as_ref().unwrap().newton.as_ref().unwrap();
        let norm = |a: &[glam::Vec4]| {
            a.iter()
                .map(|x| x.truncate().length_squared())
                .sum::<f32>()
                .sqrt()
        };
        println!(
            "alpha {:?} |f| {:.3e} |r| {:.3e}",
            nt.alphas.last(),
            norm(&nt.force),
            norm(&nt.levels[0].rhs)
        );
        report(&s2, &format!("newton {k}"));
    }
}

#[test]
#[ignore]
fn probe_hessian() {
    use drapekit::plan::{Pass, SolveOp};
    let mut scene = Scene::load(&fixture("scenes/tshirt_drape_cotton.toml")).unwrap();
    scene.solver.iterations = 1;
    if std::env::var("NOBODY").is_ok() {
        scene.bodies.clear();
    }
    let mut prep = prepare(&scene).unwrap();
    prep.frames = std::env::var("FRAMES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(60);
    prep.settle_speed = None;
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut stats = drapekit::sim::RunStats::default();
    drapekit::sim::simulate(&prep, &mut cpu, &mut stats, |_, _| Ok(())).unwrap();
    let params = drapekit::sim::phase_params(&prep, prep.frames, &stats);
    cpu.set_params(&params);
    let step = substep_params(&prep, prep.frames + 1)[0];
    cpu.run_pass(Pass::VbdInit, &step);
    cpu.run_solve_ops(
        &[
            SolveOp::ContactPlanes,
            SolveOp::Sweep { iteration: 0 },
            SolveOp::Assemble,
        ],
        &step,
    );
    let v = cpu.vbd.as_ref().unwrap();
    let nt = v.newton.as_ref().unwrap();
    let mg = &nt.structure;
    let h = &nt.levels[0].blocks;
    let el = drapekit::cpu::Elements::new(&prep.model);
    let view = el.view();
    let s = drapekit::cpu::Implicit {
        params: &params,
        step: &step,
        prev: &cpu.pos,
        target: &v.y,
        el: &view,
        planes: &v.planes,
        lambdas: &v.lambdas,
    };
    let n = prep.model.len();
    let mut rng = common::Rng::new(5);
    let dir: Vec<glam::Vec4> = (0..n)
        .map(|i| {
            if cpu.pos[i].w == 0.0 {
                glam::Vec4::ZERO
            } else {
                rng.vec3(1.0).extend(0.0)
            }
        })
        .collect();
    let eps = 1e-7f32;
    let dplus: Vec<glam::Vec4> = v.x.iter().zip(&dir).map(|(a, b)| *a + eps * *b).collect();
    let dminus: Vec<glam::Vec4> = v.x.iter().zip(&dir).map(|(a, b)| *a - eps * *b).collect();
    let mut worst = Vec::new();
    for i in 0..n {
        if cpu.pos[i].w == 0.0 {
            continue;
        }
        let fp = s.vertex_system(i, &dplus, None, &mut |_, _| {}).force;
        let fm = s.vertex_system(i, &dminus, None, &mut |_, _| {}).force;
        let fd = -(fp - fm) / (2.0 * eps);
        let filt = s.contact_filter(i, &v.x);
        if filt != glam::Mat3::IDENTITY {
            continue;
        } // skip filtered (contact) vertices
        let mut hv = glam::Vec3::ZERO;
        for b in mg.fine.offsets[i]..mg.fine.offsets[i + 1] {
            hv += h[b as usize] * dir[mg.fine.columns[b as usize] as usize].truncate();
        }
        let err = (fd - hv).length() / fd.length().max(hv.length()).max(1e-9);
        worst.push((err, i, fd.length(), hv.length()));
    }
    worst.sort_by(|a, b| b.0.partial_cmp(&a.0).unwrap());
    let mean: f32 = worst.iter().map(|w| w.0).sum::<f32>() / worst.len() as f32;
    println!("mean rel err {mean:.3e}");
    for w in worst.iter().take(10) {
        let i = w.1;
        let nseam = prep
            .model
            .seams
            .iter()
            .filter(|sm| sm.v[..3].contains(&(i as u32)))
            .count();
        println!(
            "  err {:.3} |fd| {:.3e} |Hv| {:.3e} seams {nseam} {}",
            w.0,
            w.2,
            w.3,
            prep.describe_particle(i as u32)
        );
    }
}
