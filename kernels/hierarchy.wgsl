// The multigrid hierarchy as the solve's kernels read it: one u32 array (src/gpu/hierarchy.rs
// packs it) holding a header, one header per level (level 0: the fine level) and the levels'
// structures. Composed into the solve kernels that walk a level's rows, blocks or colours.

@group(0) @binding(18) var<storage, read> hier: array<u32>;

// The header's words: the number of levels, then where the fine matrix's element slots start
// (cpu: ElementBlocks): one per spring entry, four per hinge entry, four per seam entry, four
// per membrane entry.
const HIER_LEVELS: u32 = 0u;
const HIER_SPRING_SLOTS: u32 = 1u;
const HIER_HINGE_SLOTS: u32 = 2u;
const HIER_SEAM_SLOTS: u32 = 3u;
const HIER_MEMBRANE_SLOTS: u32 = 4u;
// Level headers follow at this word, LEVEL_WORDS each.
const LEVEL_HEADER: u32 = 8u;
const LEVEL_WORDS: u32 = 16u;

// One level, as its header gives it. Every `*_at` field is a word index into `hier`.
struct Level {
    rows: u32,                   // particles on the level
    vec_base: u32,               // its first row in the rhs, e and res arrays
    offsets_at: u32,             // its matrix's row offsets (rows + 1), local block indices
    columns_at: u32,             // the column of each block
    block_base: u32,             // its first block in the blocks array
    order_at: u32,               // rows by colour
    colour_offsets_at: u32,      // colours + 1 offsets into the order
    colours: u32,
    parents_at: u32,             // levels ≥ 1: three parents on this level per row of the finer level
    weights_at: u32,             // and their weights (f32 bits)
    children_at: u32,            // levels ≥ 1: restriction's offsets (rows + 1) into
    child_items_at: u32,         // (finer row, weight bits) pairs
    galerkin_at: u32,            // levels ≥ 1: per block, offsets (blocks + 1) into
    galerkin_items_at: u32,      // (finer block, weight bits) pairs
    blocks: u32,                 // blocks of its matrix
}

fn level(l: u32) -> Level {
    let h = LEVEL_HEADER + LEVEL_WORDS * l;
    return Level(
        hier[h], hier[h + 1u], hier[h + 2u], hier[h + 3u], hier[h + 4u], hier[h + 5u],
        hier[h + 6u], hier[h + 7u], hier[h + 8u], hier[h + 9u], hier[h + 10u], hier[h + 11u],
        hier[h + 12u], hier[h + 13u], hier[h + 14u],
    );
}

// Row r's blocks are row_start(lv, r) .. row_start(lv, r + 1), its diagonal first.
fn row_start(lv: Level, r: u32) -> u32 {
    return hier[lv.offsets_at + r];
}

fn column(lv: Level, b: u32) -> u32 {
    return hier[lv.columns_at + b];
}

fn colour_start(lv: Level, c: u32) -> u32 {
    return hier[lv.colour_offsets_at + c];
}

fn order_at(lv: Level, t: u32) -> u32 {
    return hier[lv.order_at + t];
}
