// A run of the V-cycle's operations on small levels in one workgroup: the op list entries
// op.first .. op.first + op.count (src/gpu/implicit/dispatch.rs builds them), each a smooth
// (every colour of the level, forward or backward), a residual, a restriction or a
// prolongation, the workgroup striding over the rows and meeting at a barrier after each colour
// and each operation. Rows of one colour are independent, so this gives the numbers of one
// dispatch per colour (smooth.wgsl and the others), with one dispatch in place of dozens on
// levels of a few hundred particles. CPU twins: src/cpu/smooth.rs, restrict.rs, prolong.rs.

// Each entry: the operation (CYCLE_*), its level (a restriction's and a prolongation's coarse
// level), and 1 for a backward smooth.
@group(0) @binding(30) var<storage, read> op_list: array<vec4<u32>>;

// Keep in sync with src/gpu/implicit/dispatch.rs.
const CYCLE_SMOOTH: u32 = 0u;
const CYCLE_RESIDUAL: u32 = 1u;
const CYCLE_RESTRICT: u32 = 2u;
const CYCLE_PROLONG: u32 = 3u;

// One sweep over a level's colours. A level of at most CACHE_ROWS rows is smoothed in
// workgroup memory: its correction is copied in, each colour reads and writes the copy (a
// row's dozens of corrections are then near loads, not trips to memory behind a storage
// barrier), and the copy goes back at the end. The same values either way.
fn smooth_level(l: u32, backward: bool, lid: u32) {
    let lv = level(l);
    let cache = CACHE_ROWS > 0u && lv.rows <= CACHE_ROWS;
    if (cache) {
        for (var r = lid; r < lv.rows; r = r + WORKGROUP_SIZE) {
            cache_store(r, e[lv.vec_base + r].xyz);
        }
        workgroupBarrier();
        cached = true;
    }
    for (var k = 0u; k < lv.colours; k = k + 1u) {
        var c = k;
        if (backward) {
            c = lv.colours - 1u - k;
        }
        let end = colour_start(lv, c + 1u);
        for (var t = colour_start(lv, c) + lid; t < end; t = t + WORKGROUP_SIZE) {
            let r = order_at(lv, t);
            let v = smooth_row(lv, r);
            if (cache) {
                cache_store(r, v);
            } else {
                e[lv.vec_base + r] = vec4<f32>(v, 0.0);
            }
        }
        if (cache) {
            workgroupBarrier();
        } else {
            storageBarrier();
        }
    }
    if (cache) {
        cached = false;
        for (var r = lid; r < lv.rows; r = r + WORKGROUP_SIZE) {
            e[lv.vec_base + r] = vec4<f32>(cache_load(r), 0.0);
        }
        // No invocation refills the copy for the next operation before all have read it.
        workgroupBarrier();
    }
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(local_invocation_index) lid: u32) {
    if (control.done != 0u) {
        return;
    }
    for (var k = op.first; k < op.first + op.count; k = k + 1u) {
        let entry = op_list[k];
        let l = entry.y;
        switch entry.x {
            case CYCLE_SMOOTH: {
                smooth_level(l, entry.z != 0u, lid);
            }
            case CYCLE_RESIDUAL: {
                let lv = level(l);
                for (var r = lid; r < lv.rows; r = r + WORKGROUP_SIZE) {
                    res[lv.vec_base + r] = vec4<f32>(residual_row(lv, r), 0.0);
                }
            }
            case CYCLE_RESTRICT: {
                let coarse = level(l);
                let finer = level(l - 1u);
                for (var c = lid; c < coarse.rows; c = c + WORKGROUP_SIZE) {
                    rhs[coarse.vec_base + c] = restrict_row(coarse, finer, c);
                    e[coarse.vec_base + c] = vec4<f32>(0.0);
                }
            }
            default: {
                let coarse = level(l);
                let finer = level(l - 1u);
                for (var i = lid; i < finer.rows; i = i + WORKGROUP_SIZE) {
                    let at = finer.vec_base + i;
                    e[at] = e[at] + vec4<f32>(prolong_row(coarse, i), 0.0);
                }
            }
        }
        storageBarrier();
    }
}
