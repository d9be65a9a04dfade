// A deforming body's signed distance, normal and surface velocity at a world point, by inverse
// skinning into its rest pose. Composed after the stages that collide with bodies
// (collide_body, contact_planes), which pass their SDF texture in and bind the substep's
// `step` (its `parts` are the collision parts' poses). CPU twin: src/cpu/deformed_body.rs,
// where the method is described; the functions here follow it line for line.
//
// The body's words (its SDF nodes, then the blocks of body::deformed_sdf) are r32float texels
// from its first node (BodyParams.sdf_dims.w); integers are stored as their bits.

// Most fixed-point refinements of the rest point (cpu: REFINEMENTS).
const DEFORMED_REFINEMENTS: u32 = 12u;
// A refinement that moves the rest point less than this, in m, has settled (cpu: SETTLED_STEP).
const DEFORMED_SETTLED_STEP: f32 = 1e-5;
// Words per vertex of the weights block (body::deformed_sdf::WEIGHT_WORDS).
const DEFORMED_WEIGHT_WORDS: u32 = 5u;

// The contact at a world point: φ (SDF_FAR: no part is near), the unit world normal and the
// surface velocity field around it, v(p) = linear + angular × (p − center).
struct DeformedSample {
    phi: f32,
    normal: vec3<f32>,
    center: vec3<f32>,
    linear: vec3<f32>,
    angular: vec3<f32>,
}

fn deformed_velocity_at(s: DeformedSample, p: vec3<f32>) -> vec3<f32> {
    return s.linear + cross(s.angular, p - s.center);
}

fn body_word(sdf: texture_2d<f32>, body: BodyParams, i: u32) -> f32 {
    return textureLoad(sdf, texel(body.sdf_dims.w + i), 0).x;
}

fn body_word_u(sdf: texture_2d<f32>, body: BodyParams, i: u32) -> u32 {
    return bitcast<u32>(body_word(sdf, body, i));
}

fn body_word3(sdf: texture_2d<f32>, body: BodyParams, i: u32) -> vec3<f32> {
    return vec3<f32>(body_word(sdf, body, i), body_word(sdf, body, i + 1u), body_word(sdf, body, i + 2u));
}

// Offsets of the blocks after the SDF (words, from the body's first).
struct DeformedLayout {
    nodes: u32,
    vertices: u32,
    triangles: u32,
    weights: u32,
    boxes: u32,
}

fn deformed_layout(sdf: texture_2d<f32>, body: BodyParams) -> DeformedLayout {
    let d = body.sdf_dims;
    let nodes = d.x * d.y * d.z;
    let header = 2u * nodes;
    let vertex_count = body_word_u(sdf, body, header);
    let triangle_count = body_word_u(sdf, body, header + 1u);
    let vertices = header + 2u;
    let triangles = vertices + 3u * vertex_count;
    let weights = triangles + 3u * triangle_count;
    return DeformedLayout(nodes, vertices, triangles, weights, weights + DEFORMED_WEIGHT_WORDS * vertex_count);
}

// Barycentric coordinates of the point of triangle (a, b, c) closest to p (Ericson, Real-Time
// Collision Detection 5.1.5).
fn closest_barycentric(p: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> vec3<f32> {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) {
        return vec3<f32>(1.0, 0.0, 0.0);
    }
    let bp = p - b;
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) {
        return vec3<f32>(0.0, 1.0, 0.0);
    }
    let vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        let v = d1 / (d1 - d3);
        return vec3<f32>(1.0 - v, v, 0.0);
    }
    let cp = p - c;
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) {
        return vec3<f32>(0.0, 0.0, 1.0);
    }
    let vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        let w = d2 / (d2 - d6);
        return vec3<f32>(1.0 - w, 0.0, w);
    }
    let va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return vec3<f32>(0.0, 1.0 - w, w);
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    return vec3<f32>(1.0 - v - w, v, w);
}

// The parts blended at one rest point: A = Σ cₖRₖ, b = Σ cₖtₖ, and the blended velocity
// field's terms at world point x; `valid` is false outside the grid.
struct Blend {
    a: mat3x3<f32>,
    b: vec3<f32>,
    linear: vec3<f32>,
    angular: vec3<f32>,
    valid: bool,
}

// The skin weights at rest point y (those at the closest point of the triangle nearest to y's
// grid node), blended over the parts' poses.
fn blend_at(sdf: texture_2d<f32>, body: BodyParams, l: DeformedLayout, y: vec3<f32>, x: vec3<f32>) -> Blend {
    var out = Blend(mat3x3<f32>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0)), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), false);
    let d = body.sdf_dims;
    let g = (y - body.sdf_origin.xyz) / body.sdf_origin.w;
    let last = vec3<f32>(d.xyz) - vec3<f32>(1.0);
    if (any(g < vec3<f32>(0.0)) || any(g > last)) {
        return out;
    }
    let c = vec3<u32>(min(floor(g + vec3<f32>(0.5)), last));
    let node = c.x + d.x * (c.y + d.y * c.z);
    let t = body_word_u(sdf, body, l.nodes + node);
    let corners = vec3<u32>(
        body_word_u(sdf, body, l.triangles + 3u * t),
        body_word_u(sdf, body, l.triangles + 3u * t + 1u),
        body_word_u(sdf, body, l.triangles + 3u * t + 2u),
    );
    let bary = closest_barycentric(
        y,
        body_word3(sdf, body, l.vertices + 3u * corners.x),
        body_word3(sdf, body, l.vertices + 3u * corners.y),
        body_word3(sdf, body, l.vertices + 3u * corners.z),
    );
    for (var k = 0u; k < 3u; k = k + 1u) {
        let base = l.weights + DEFORMED_WEIGHT_WORDS * corners[k];
        let packed = body_word_u(sdf, body, base);
        for (var slot = 0u; slot < 4u; slot = slot + 1u) {
            let weight = bary[k] * body_word(sdf, body, base + 1u + slot);
            if (weight == 0.0) {
                continue;
            }
            let pose = step.parts[body.first_part + ((packed >> (8u * slot)) & 0xffu)];
            out.a = out.a + mat3x3<f32>(pose.x.xyz, pose.y.xyz, pose.z.xyz) * weight;
            out.b = out.b + pose.translation.xyz * weight;
            let offset = x - pose.translation.xyz;
            out.linear = out.linear + (pose.velocity.xyz + cross(pose.angular_velocity.xyz, offset)) * weight;
            out.angular = out.angular + pose.angular_velocity.xyz * weight;
        }
    }
    out.valid = true;
    return out;
}

// A⁻¹ through the adjugate; `ok` is false when A is singular.
struct Inverse {
    m: mat3x3<f32>,
    ok: bool,
}

fn inverse3(a: mat3x3<f32>) -> Inverse {
    let r0 = cross(a[1], a[2]);
    let r1 = cross(a[2], a[0]);
    let r2 = cross(a[0], a[1]);
    let det = dot(a[0], r0);
    // Rows of the adjugate are the cross products of the columns.
    let adj = transpose(mat3x3<f32>(r0, r1, r2));
    return Inverse(mat3x3<f32>(adj[0] / det, adj[1] / det, adj[2] / det), abs(det) > 1e-12);
}

// The rest point that part k maps x back to (cpu: rest_point); ok is false where x is outside
// the part's box or the refinement cannot start.
struct RestPoint {
    y: vec3<f32>,
    ok: bool,
}

fn deformed_rest_point(sdf: texture_2d<f32>, body: BodyParams, l: DeformedLayout, k: u32, x: vec3<f32>) -> RestPoint {
    let pose = step.parts[body.first_part + k];
    let rel = x - pose.translation.xyz;
    var y = vec3<f32>(dot(pose.x.xyz, rel), dot(pose.y.xyz, rel), dot(pose.z.xyz, rel));
    let lo = body_word3(sdf, body, l.boxes + 6u * k);
    let hi = body_word3(sdf, body, l.boxes + 6u * k + 3u);
    if (any(y < lo) || any(y > hi)) {
        return RestPoint(y, false);
    }
    var settled = false;
    var last = vec3<f32>(0.0);
    for (var r = 0u; r < DEFORMED_REFINEMENTS; r = r + 1u) {
        let blend = blend_at(sdf, body, l, y, x);
        if (!blend.valid) {
            break;
        }
        let inv = inverse3(blend.a);
        if (!inv.ok) {
            break;
        }
        var step = inv.m * (x - blend.b) - y;
        // A step that turns back on the last one is overshooting an oscillation: halve it.
        if (dot(step, last) < 0.0) {
            step = step * 0.5;
        }
        y = y + step;
        last = step;
        settled = true;
        if (length(step) < DEFORMED_SETTLED_STEP) {
            break;
        }
    }
    return RestPoint(y, settled);
}

// One part's answer at x (cpu: Candidate): the sample from its rest point and, where the part
// has x outside, how far x is from where the rest surface point nearest that rest point skins
// to (SDF_FAR: not computed, or it cannot be skinned); valid is false where the part has none.
struct DeformedCandidate {
    sample: DeformedSample,
    surface_distance: f32,
    valid: bool,
}

fn deformed_candidate(sdf: texture_2d<f32>, body: BodyParams, l: DeformedLayout, k: u32, x: vec3<f32>) -> DeformedCandidate {
    var out = DeformedCandidate(DeformedSample(SDF_FAR, vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0)), SDF_FAR, false);
    let rest = deformed_rest_point(sdf, body, l, k, x);
    if (!rest.ok) {
        return out;
    }
    let y = rest.y;
    let blend = blend_at(sdf, body, l, y, x);
    if (!blend.valid) {
        return out;
    }
    // Where the rest point skins to now; a candidate that has not settled within the
    // thickness does not describe the surface near x.
    if (length(blend.a * y + blend.b - x) > body.thickness) {
        return out;
    }
    let s = sdf_sample(sdf, body.sdf_origin, body.sdf_dims, y);
    let inv = inverse3(blend.a);
    if (!inv.ok) {
        return out;
    }
    let n = transpose(inv.m) * s.xyz;
    let len = length(n);
    if (len <= 1e-12) {
        return out;
    }
    // Outside: the rest surface point nearest y (y − φ∇φ̂), skinned.
    if (s.w >= 0.0) {
        let g = length(s.xyz);
        let on_rest = y - s.w * select(vec3<f32>(0.0), s.xyz / g, g > 0.0);
        let at_surface = blend_at(sdf, body, l, on_rest, x);
        if (at_surface.valid) {
            out.surface_distance = length(at_surface.a * on_rest + at_surface.b - x);
        }
    }
    out.sample = DeformedSample(s.w, n / len, x, blend.linear, blend.angular);
    out.valid = true;
    return out;
}

// The deforming body's contact at world point x: of the parts' answers the smallest φ wins,
// except an inside claim refuted by a part that has x outside and skinned a surface point to
// within the claimed depth less the thickness; the deepest claim if it stands, else the
// shallowest, else the nearest outside answer (cpu: deformed_sample, which says why).
fn deformed_sample(sdf: texture_2d<f32>, body: BodyParams, x: vec3<f32>) -> DeformedSample {
    let l = deformed_layout(sdf, body);
    let far = DeformedSample(SDF_FAR, vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    var deepest = far;
    var shallowest = far;
    var inside = false;
    var outside = far;
    var nearest_skinned_surface = SDF_FAR;
    for (var k = 0u; k < body.parts; k = k + 1u) {
        let c = deformed_candidate(sdf, body, l, k, x);
        if (!c.valid) {
            continue;
        }
        let phi = c.sample.phi;
        if (phi < 0.0) {
            if (!inside || phi < deepest.phi) {
                deepest = c.sample;
            }
            if (!inside || phi > shallowest.phi) {
                shallowest = c.sample;
            }
            inside = true;
        } else {
            nearest_skinned_surface = min(nearest_skinned_surface, c.surface_distance);
            if (phi < outside.phi) {
                outside = c.sample;
            }
        }
    }
    if (inside && -deepest.phi <= nearest_skinned_surface + body.thickness) {
        return deepest;
    }
    if (inside && -shallowest.phi <= nearest_skinned_surface + body.thickness) {
        return shallowest;
    }
    return outside;
}
