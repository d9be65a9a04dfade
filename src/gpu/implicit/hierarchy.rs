//! The multigrid hierarchy packed into one u32 array for the solve's kernels
//! (`kernels/hierarchy.wgsl` reads it): a header, one header per level (level 0: the fine
//! level, with its colour order for the sweeps; without coarse levels the only one), then every
//! level's matrix pattern, colour order, transfer lists and Galerkin lists, and the fine
//! matrix's element slots. Floats (weights) are stored as their bits.

use crate::model::multigrid::{BlockPattern, Level};
use crate::model::ClothModel;

/// Where the level headers start, in words (as LEVEL_HEADER in hierarchy.wgsl).
const LEVEL_HEADER: usize = 8;
/// Words per level header (as LEVEL_WORDS in hierarchy.wgsl).
const LEVEL_WORDS: usize = 16;

/// What the host keeps of a level to build dispatches and read arrays back.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LevelInfo {
    /// Particles on the level.
    pub rows: u32,
    /// Its first row in the rhs, e and res arrays.
    pub vec_base: u32,
    /// Its first block in the blocks array.
    pub block_base: u32,
    /// Blocks of its matrix.
    pub blocks: u32,
    /// Each colour's first entry in the level's colour order, and its rows.
    pub colours: Vec<(u32, u32)>,
}

/// The packed hierarchy.
pub struct Packed {
    /// The words the kernels read.
    pub words: Vec<u32>,
    /// Every level, the fine level first.
    pub levels: Vec<LevelInfo>,
    /// Rows of all levels together.
    pub rows: u32,
    /// Blocks of all levels together.
    pub blocks: u32,
    /// The column of every block of all levels, level after level.
    pub columns: Vec<u32>,
}

/// `data` appended to `words`; returns where it starts.
fn append(words: &mut Vec<u32>, data: impl IntoIterator<Item = u32>) -> u32 {
    let at = words.len() as u32;
    words.extend(data);
    at
}

fn pairs(items: &[(u32, f32)]) -> impl Iterator<Item = u32> + '_ {
    items.iter().flat_map(|&(i, w)| [i, w.to_bits()])
}

/// Packs `model`'s hierarchy (its fine level alone when it has no coarse levels).
pub fn pack(model: &ClothModel) -> Packed {
    let mg = model.multigrid.as_deref();
    let coloring = model.vertex_coloring();
    let empty = BlockPattern {
        offsets: vec![0; model.len() + 1],
        columns: Vec::new(),
    };
    let fine = mg.map_or(&empty, |m| &m.fine);
    let coarse: &[Level] = mg.map_or(&[], |m| &m.levels);
    let count = 1 + coarse.len();
    let mut words = vec![0u32; LEVEL_HEADER + LEVEL_WORDS * count];
    words[0] = count as u32;
    if let Some(m) = mg {
        let b = &m.element_blocks;
        words[1] = append(&mut words, b.springs.iter().copied());
        words[2] = append(&mut words, b.hinges.iter().flatten().copied());
        words[3] = append(&mut words, b.seams.iter().flatten().copied());
        words[4] = append(&mut words, b.membranes.iter().flatten().copied());
    }
    let (mut rows, mut blocks) = (0u32, 0u32);
    let mut columns = Vec::new();
    let mut levels = Vec::with_capacity(count);
    for l in 0..count {
        let (pattern, order, colour_offsets) = match l {
            0 => (fine, &coloring.order, &coloring.offsets),
            _ => {
                let lv = &coarse[l - 1];
                (&lv.pattern, &lv.order, &lv.color_offsets)
            }
        };
        let mut header = [0u32; LEVEL_WORDS];
        header[0] = pattern.rows() as u32;
        header[1] = rows;
        header[2] = append(&mut words, pattern.offsets.iter().copied());
        header[3] = append(&mut words, pattern.columns.iter().copied());
        columns.extend(&pattern.columns);
        header[4] = blocks;
        header[5] = append(&mut words, order.iter().copied());
        header[6] = append(&mut words, colour_offsets.iter().copied());
        header[7] = (colour_offsets.len() - 1) as u32;
        if l > 0 {
            let lv = &coarse[l - 1];
            header[8] = append(&mut words, lv.parents.iter().flatten().copied());
            header[9] = append(&mut words, lv.weights.iter().flatten().map(|w| w.to_bits()));
            header[10] = append(&mut words, lv.children.offsets.iter().copied());
            header[11] = append(&mut words, pairs(&lv.children.items));
            header[12] = append(&mut words, lv.galerkin.offsets.iter().copied());
            header[13] = append(&mut words, pairs(&lv.galerkin.items));
        }
        header[14] = pattern.blocks() as u32;
        let at = LEVEL_HEADER + LEVEL_WORDS * l;
        words[at..at + LEVEL_WORDS].copy_from_slice(&header);
        levels.push(LevelInfo {
            rows: header[0],
            vec_base: rows,
            block_base: blocks,
            blocks: header[14],
            colours: colour_offsets
                .windows(2)
                .map(|w| (w[0], w[1] - w[0]))
                .collect(),
        });
        rows += header[0];
        blocks += header[14];
    }
    Packed {
        words,
        levels,
        rows,
        blocks,
        columns,
    }
}
