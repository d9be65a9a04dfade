//! A substep's solve, `plan::implicit_schedule`'s operations, expanded into the dispatches the
//! GPU encodes: which kernel, which `OpParams` entry (level, colour, slot) and how many
//! workgroups. The expansion is built once at setup and encoded per substep.
//!
//! Most operations are one dispatch over particles (or a level's rows or blocks). Sweeps and
//! smoothing on large levels are one dispatch per colour. Level operations over at most
//! `small_rows` rows (the coarse levels, and on software adapters the whole V-cycle) run back to
//! back in one single-workgroup `coarse_cycle` dispatch, which loops over their colours and rows
//! with barriers: the same numbers as a dispatch per colour, at the cost of one dispatch.
//! Reductions whose result a later dispatch needs are split where all workgroups must have
//! finished: partials per workgroup first, then their in-order sum (`pcg_direction`,
//! `pcg_step`, `line_search`, `reduce_residual`).

use super::hierarchy::LevelInfo;
use super::kernels::SolveKernel;
use super::layout::OpParams;
use crate::model::layout::WORKGROUP_SIZE;
use crate::plan::SolveOp;
use std::collections::HashMap;

/// Workgroups (x, y) for `threads` invocations: 2D past `max_x` per dimension.
pub fn dispatch_for(threads: u32, max_x: u32) -> (u32, u32) {
    let total = threads.div_ceil(WORKGROUP_SIZE).max(1);
    if total <= max_x {
        (total, 1)
    } else {
        (max_x, total.div_ceil(max_x))
    }
}

/// `coarse_cycle`'s operations (as CYCLE_* in coarse_cycle.wgsl).
const CYCLE_SMOOTH: u32 = 0;
const CYCLE_RESIDUAL: u32 = 1;
const CYCLE_RESTRICT: u32 = 2;
const CYCLE_PROLONG: u32 = 3;

/// One dispatch of the solve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Dispatch {
    /// The kernel.
    pub kernel: SolveKernel,
    /// Its `OpParams` entry.
    pub op: u32,
    /// Workgroups in x and y.
    pub groups: (u32, u32),
}

/// The distinct `OpParams` entries and `coarse_cycle` op lists the dispatches use.
#[derive(Default)]
pub struct Tables {
    /// Every entry, in first-use order.
    pub params: Vec<OpParams>,
    index: HashMap<OpParams, u32>,
    /// Every op list, one after another.
    pub op_list: Vec<[u32; 4]>,
    lists: HashMap<Vec<[u32; 4]>, u32>,
}

impl Tables {
    fn entry(&mut self, p: OpParams) -> u32 {
        *self.index.entry(p).or_insert_with(|| {
            self.params.push(p);
            self.params.len() as u32 - 1
        })
    }

    /// Where `list` starts in `op_list` (appended if new).
    fn list(&mut self, list: Vec<[u32; 4]>) -> u32 {
        let op_list = &mut self.op_list;
        *self.lists.entry(list.clone()).or_insert_with(|| {
            op_list.extend(&list);
            (op_list.len() - list.len()) as u32
        })
    }
}

/// Expands operations into dispatches.
pub struct Builder<'a> {
    /// Every level, the fine level first.
    pub levels: &'a [LevelInfo],
    /// Level operations over at most this many rows run in `coarse_cycle`.
    pub small_rows: u32,
    /// The adapter's workgroups per dispatch dimension.
    pub max_groups_x: u32,
    /// The entries the dispatches use.
    pub tables: &'a mut Tables,
    /// The conjugate-gradient iteration (its parity selects the r·z slot).
    pub cg: u32,
}

impl Builder<'_> {
    fn push(&mut self, out: &mut Vec<Dispatch>, kernel: SolveKernel, p: OpParams, threads: u32) {
        let op = self.tables.entry(p);
        let groups = dispatch_for(threads, self.max_groups_x);
        out.push(Dispatch { kernel, op, groups });
    }

    fn level(&self, l: u32) -> &LevelInfo {
        &self.levels[l as usize]
    }

    /// Copies a level's blocks, once written, to the texels the kernels read them from.
    pub fn publish(&mut self, out: &mut Vec<Dispatch>, level: u32) {
        let p = OpParams {
            level,
            ..Default::default()
        };
        let blocks = self.level(level).blocks;
        self.push(out, SolveKernel::PublishBlocks, p, blocks);
    }

    /// The `coarse_cycle` entry of a level operation whose rows are few enough.
    fn cycle_entry(&self, op: SolveOp) -> Option<[u32; 4]> {
        let (entry, rows) = match op {
            SolveOp::Smooth { level, backward } => (
                [CYCLE_SMOOTH, level, backward as u32, 0],
                self.level(level).rows,
            ),
            SolveOp::Residual { level } => ([CYCLE_RESIDUAL, level, 0, 0], self.level(level).rows),
            SolveOp::Restrict { to } => ([CYCLE_RESTRICT, to, 0, 0], self.level(to).rows),
            SolveOp::Prolong { from } => ([CYCLE_PROLONG, from, 0, 0], self.level(from - 1).rows),
            _ => return None,
        };
        (rows <= self.small_rows).then_some(entry)
    }

    /// The dispatches of `ops`, in order.
    pub fn expand(&mut self, ops: &[SolveOp]) -> Vec<Dispatch> {
        let mut out = Vec::new();
        let mut cycle: Vec<[u32; 4]> = Vec::new();
        for &op in ops {
            if let Some(entry) = self.cycle_entry(op) {
                cycle.push(entry);
                continue;
            }
            self.flush(&mut cycle, &mut out);
            self.expand_op(op, &mut out);
        }
        self.flush(&mut cycle, &mut out);
        out
    }

    fn flush(&mut self, cycle: &mut Vec<[u32; 4]>, out: &mut Vec<Dispatch>) {
        if cycle.is_empty() {
            return;
        }
        let count = cycle.len() as u32;
        let first = self.tables.list(std::mem::take(cycle));
        let op = self.tables.entry(OpParams {
            first,
            count,
            ..Default::default()
        });
        out.push(Dispatch {
            kernel: SolveKernel::CoarseCycle,
            op,
            groups: (1, 1),
        });
    }

    fn expand_op(&mut self, op: SolveOp, out: &mut Vec<Dispatch>) {
        use SolveKernel as K;
        let n = self.level(0).rows;
        let plain = OpParams::default();
        let on_level = |level: u32| OpParams {
            level,
            ..Default::default()
        };
        let colours = |b: &Self, level: u32, slot: u32| -> Vec<(OpParams, u32)> {
            (b.level(level).colours.iter())
                .map(|&(first, count)| {
                    let p = OpParams {
                        level,
                        first,
                        count,
                        slot,
                        ..Default::default()
                    };
                    (p, count)
                })
                .collect()
        };
        match op {
            // No kernel: `bench convergence`'s one-level comparison runs on the CPU only, and
            // the solver refuses it (`ImplicitSolve::new`, `run_solve_ops`).
            SolveOp::BlockJacobi => {}
            SolveOp::ContactPlanes => self.push(out, K::ContactPlanes, plain, n),
            SolveOp::Sweep { iteration } => {
                for (p, count) in colours(self, 0, iteration) {
                    self.push(out, K::Sweep, p, count);
                }
            }
            SolveOp::Assemble => {
                self.push(out, K::Assemble, plain, n);
                self.publish(out, 0);
            }
            SolveOp::CoarseOperator { level } => {
                let blocks = self.level(level).blocks;
                self.push(out, K::CoarseOperator, on_level(level), blocks);
                self.publish(out, level);
            }
            SolveOp::PcgStart => {
                self.cg = 0;
                self.push(out, K::PcgStart, plain, n);
            }
            SolveOp::Smooth { level, backward } => {
                let mut list = colours(self, level, 0);
                if backward {
                    list.reverse();
                }
                for (p, count) in list {
                    self.push(out, K::Smooth, p, count);
                }
            }
            SolveOp::Residual { level } => {
                let rows = self.level(level).rows;
                self.push(out, K::LevelResidual, on_level(level), rows);
            }
            SolveOp::Restrict { to } => {
                let rows = self.level(to).rows;
                self.push(out, K::Restrict, on_level(to), rows);
            }
            SolveOp::Prolong { from } => {
                let rows = self.level(from - 1).rows;
                self.push(out, K::Prolong, on_level(from), rows);
            }
            SolveOp::PcgDirection { first } => {
                let p = OpParams {
                    slot: self.cg % 2,
                    flag: first as u32,
                    ..Default::default()
                };
                self.push(out, K::PcgDot, plain, n);
                self.push(out, K::PcgDirection, p, n);
            }
            SolveOp::PcgMatVec => self.push(out, K::PcgMatVec, plain, n),
            SolveOp::PcgStep => {
                let p = OpParams {
                    slot: self.cg % 2,
                    ..Default::default()
                };
                self.push(out, K::PcgStep, p, n);
                self.cg += 1;
            }
            SolveOp::CorrectionFilter => self.push(out, K::CorrectionFilter, plain, n),
            SolveOp::LineEnergy => self.push(out, K::LineEnergy, plain, n),
            SolveOp::LineSlopes => self.push(out, K::LineSlopes, plain, n),
            SolveOp::LineSearch => self.push(out, K::LineSearch, plain, 1),
            SolveOp::ApplyCorrection => self.push(out, K::ApplyCorrection, plain, n),
            SolveOp::ForceResidual => {
                self.push(out, K::ForceResidual, plain, n);
                self.push(out, K::ReduceResidual, plain, 1);
            }
            SolveOp::CheckConverged => {
                let p = OpParams {
                    flag: 1,
                    ..Default::default()
                };
                self.push(out, K::ReduceResidual, p, 1);
            }
        }
    }
}
