// The change of the incremental potential G along the correction c at each of the line
// search's step lengths, counted at each vertex (its own terms: inertia, air damping, contact,
// friction; and the elements it owns: a spring at its lower-numbered end, a hinge, a membrane
// triangle and a seam pair at their first vertex) and summed per workgroup by tree_sum (xyz:
// one step length each; w: the scale of the full step's change, which bounds its rounding).
// Each change is a difference of nearby quantities, not G(x + αc) − G(x), so it keeps its
// precision however large G is; a hinge's energies and friction's potentials are differenced,
// and their two values count in the scale. CPU twin: line_energy in src/cpu/line_energy.rs and
// Implicit::energy_change in src/cpu/implicit_terms/energy_change.rs.

@group(0) @binding(21) var<storage, read> correction: array<vec4<f32>>;
@group(0) @binding(27) var<storage, read_write> partials: array<vec4<f32>>;

// The step lengths the line search tries, in order (cpu: LINE_ALPHAS).
const LINE_ALPHAS: vec3<f32> = vec3<f32>(1.0, 0.5, 0.25);

// Smoothed Coulomb friction's potential of a slip s, with ε the slip over the step below which
// friction is static.
fn friction_f0(s: f32, eps: f32) -> f32 {
    if (s < eps) {
        return s * s / (2.0 * eps);
    }
    return s - 0.5 * eps;
}

// Contact and friction's share of energy_change at free vertex i.
fn contact_change(i: u32, di: vec3<f32>, ci: vec3<f32>, out: ptr<function, vec4<f32>>) {
    if (params.num_bodies == 0u) {
        return;
    }
    let k_c = contact_stiffness(i);
    for (var b = 0u; b < params.num_bodies; b = b + 1u) {
        let body = params.bodies[b];
        let pl = plane(b, i);
        let n = pl.xyz;
        let depth = body.thickness - (pl.w + dot(n, di));
        let lambda = lambdas[i][b];
        let eps = body.friction_slip_speed * params.dt;
        let sl = slip(b, i, di, n);
        let dslip = ci - dot(ci, n) * n;
        for (var k = 0u; k < 3u; k = k + 1u) {
            let a = LINE_ALPHAS[k];
            let depth2 = depth - a * dot(n, ci);
            let p0 = max(depth, 0.0);
            let p1 = max(depth2, 0.0);
            let v = 0.5 * k_c * (p1 - p0) * (p1 + p0);
            (*out)[k] = (*out)[k] + v;
            add_scale(k, abs(v), out);
            if (lambda > 0.0 && body.friction > 0.0) {
                let s0 = length(sl);
                let s1 = length(sl + a * dslip);
                (*out)[k] = (*out)[k] + body.friction * lambda * (friction_f0(s1, eps) - friction_f0(s0, eps));
                let e0 = body.friction * lambda * friction_f0(s0, eps);
                let e1 = body.friction * lambda * friction_f0(s1, eps);
                add_scale(k, e0 + e1, out);
            }
        }
    }
}

// Adds a term's size to the scale (w) for the full step (k = 0).
fn add_scale(k: u32, size: f32, out: ptr<function, vec4<f32>>) {
    if (k == 0u) {
        (*out).w = (*out).w + size;
    }
}

fn energy_change(i: u32) -> vec4<f32> {
    let h = params.dt;
    var out = vec4<f32>(0.0);
    let p = prev(i);
    let di = disp[i].xyz;
    let ci = correction[i].xyz;
    if (p.w != 0.0) {
        let mass = 1.0 / p.w;
        let inertia = mass / (h * h);
        let air = params.air_damping * mass / h;
        let to_target = di - inertial[i].xyz;
        for (var k = 0u; k < 3u; k = k + 1u) {
            let a = LINE_ALPHAS[k];
            let sq = a * a * dot(ci, ci);
            let v = inertia * (a * dot(ci, to_target) + 0.5 * sq) + air * (a * dot(ci, di) + 0.5 * sq);
            out[k] = out[k] + v;
            add_scale(k, abs(v), &out);
        }
        contact_change(i, di, ci, &out);
    }

    let first = textureLoad(spring_offsets, texel(i), 0).x;
    let end = textureLoad(spring_offsets, texel(i + 1u), 0).x;
    for (var t = first; t < end; t = t + 1u) {
        let s = unpack_spring(textureLoad(springs, texel(t), 0));
        let j = s.other;
        if (j < i) {
            continue;
        }
        let start = p.xyz - prev(j).xyz;
        let change = di - disp[j].xyz;
        let e = start + change;
        let dc = ci - correction[j].xyz;
        let len = length(e);
        let start_len = length(start);
        var n = vec3<f32>(0.0);
        if (start_len > 1e-12) {
            n = start / start_len;
        }
        for (var k = 0u; k < 3u; k = k + 1u) {
            let a = LINE_ALPHAS[k];
            let grow = 2.0 * a * dot(e, dc) + a * a * dot(dc, dc);
            let len2 = length(e + a * dc);
            // l' − l = (|e'|² − |e|²)/(l' + l): no cancellation of two lengths.
            var dl = 0.0;
            if (len + len2 > 0.0) {
                dl = grow / (len + len2);
            }
            let rest = s.rest_length;
            let law = StretchLaw(params.euler_onset / rest, params.buckled_fraction, 0.0, 0.0);
            let stretch = law_energy_change(law, s.stiffness, len - rest, len2 - rest, len + len2 - 2.0 * rest, dl);
            let dn = a * dot(n, dc);
            let v = stretch + 0.5 * s.damping / h * dn * (2.0 * dot(n, change) + dn);
            out[k] = out[k] + v;
            add_scale(k, abs(v), &out);
        }
    }
    add_hinge_changes(i, &out);
    add_membrane_changes(i, &out);
    add_seam_changes(i, &out);
    return out;
}

// section bending
fn hinge_energy(hinge: Hinge, c: array<vec3<f32>, 4>, a: f32) -> f32 {
    let t = hinge_frame_at(hinge, c, a);
    if (!t.valid) {
        return 0.0;
    }
    return hinge.rest_weight * hinge_psi(t.sin_half, hinge.rest_sin_half);
}

fn add_hinge_changes(i: u32, out: ptr<function, vec4<f32>>) {
    let first = textureLoad(hinge_offsets, texel(i), 0).x;
    let end = textureLoad(hinge_offsets, texel(i + 1u), 0).x;
    for (var t = first; t < end; t = t + 1u) {
        let r = textureLoad(hinge_refs, texel(t), 0).x;
        if (r % 4u != 0u) {
            continue;
        }
        let hinge = hinge_at(r / 4u);
        let v = hinge.v;
        let c = array<vec3<f32>, 4>(correction[v.x].xyz, correction[v.y].xyz, correction[v.z].xyz, correction[v.w].xyz);
        let before = hinge_energy(hinge, c, 0.0);
        for (var k = 0u; k < 3u; k = k + 1u) {
            let after = hinge_energy(hinge, c, LINE_ALPHAS[k]);
            (*out)[k] = (*out)[k] + (after - before);
            add_scale(k, abs(after) + abs(before), out);
        }
    }
}
// else bending
fn add_hinge_changes(i: u32, out: ptr<function, vec4<f32>>) {}
// end bending

// section membrane
// Σ c_r·c[v_r] of the correction, as membrane_start_image does for xₙ.
fn membrane_correction_image(m: Membrane, c: vec3<f32>) -> vec3<f32> {
    let c0 = correction[m.v.x].xyz;
    return c.y * (correction[m.v.y].xyz - c0) + c.z * (correction[m.v.z].xyz - c0);
}

// Each membrane's change, counted at its first vertex (cpu: the membrane loop of
// Implicit::energy_change).
fn add_membrane_changes(i: u32, out: ptr<function, vec4<f32>>) {
    let h = params.dt;
    let first = textureLoad(membrane_offsets, texel(i), 0).x;
    let end = textureLoad(membrane_offsets, texel(i + 1u), 0).x;
    for (var t = first; t < end; t = t + 1u) {
        let r = textureLoad(membrane_refs, texel(t), 0).x;
        if (r % 4u != 0u) {
            continue;
        }
        let m = membrane_at(r / 4u);
        let st = membrane_step(m);
        let du = membrane_correction_image(m, st.a);
        let dv = membrane_correction_image(m, st.b);
        for (var k = 0u; k < 3u; k = k + 1u) {
            let a = LINE_ALPHAS[k];
            let v = membrane_energy_change(st, m, a * du, a * dv, h);
            (*out)[k] = (*out)[k] + v;
            add_scale(k, abs(v), out);
        }
    }
}
// else membrane
fn add_membrane_changes(i: u32, out: ptr<function, vec4<f32>>) {}
// end membrane

// section seams
fn add_seam_changes(i: u32, out: ptr<function, vec4<f32>>) {
    let h = params.dt;
    let first = textureLoad(seam_offsets, texel(i), 0).x;
    let end = textureLoad(seam_offsets, texel(i + 1u), 0).x;
    for (var t = first; t < end; t = t + 1u) {
        let r = textureLoad(seam_refs, texel(t), 0).x;
        if (r % 4u != 0u) {
            continue;
        }
        let s = seam_at(r / 4u);
        let g = seam_gap(s);
        let w = s.weight;
        let dg = (1.0 - w) * correction[s.v.y].xyz + w * correction[s.v.z].xyz - correction[s.v.x].xyz;
        let rest = rest_gap(s);
        for (var k = 0u; k < 3u; k = k + 1u) {
            let a = LINE_ALPHAS[k];
            let damping = 0.5 * s.damping / h * (2.0 * a * dot(g.opening, dg) + a * a * dot(dg, dg));
            var spring = 0.0;
            if (rest <= 0.0) {
                spring = 0.5 * s.stiffness * (2.0 * a * dot(g.gap, dg) + a * a * dot(dg, dg));
            } else {
                let o0 = max(length(g.gap) - rest, 0.0);
                let o1 = max(length(g.gap + a * dg) - rest, 0.0);
                spring = 0.5 * s.stiffness * (o1 - o0) * (o1 + o0);
            }
            (*out)[k] = (*out)[k] + (damping + spring);
            add_scale(k, abs(damping) + abs(spring), out);
        }
    }
}
// else seams
fn add_seam_changes(i: u32, out: ptr<function, vec4<f32>>) {}
// end seams

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    if (control.done != 0u) {
        return;
    }
    let i = particle_index(gid, groups);
    var lane = vec4<f32>(0.0);
    if (i < params.num_particles) {
        lane = energy_change(i);
    }
    lanes[lid] = lane;
    let total = tree_sum(lid);
    if (lid == 0u) {
        partials[group_index(wid, groups)] = total;
    }
}
