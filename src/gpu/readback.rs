//! Reading GPU state back through MAP_READ staging buffers: the particle state at output
//! frames, and forces and hash tables for the parity tests.

use super::solver::GpuSolver;
use super::texels::TexelArray;
use crate::error::Error;
use glam::Vec4;

/// Counts, starts and sorted particle indices of the spatial hash, as read back.
pub type HashTables = (Vec<u32>, Vec<u32>, Vec<u32>);

impl GpuSolver {
    /// Reads back the spatial hash: counts, starts and sorted particle indices (for parity
    /// tests of the self-collision stages).
    pub fn hash_tables(&self) -> Result<HashTables, Error> {
        let h = self
            .hash
            .as_ref()
            .ok_or_else(|| Error::Gpu("self-collision is not in the plan".into()))?;
        Ok((
            self.read_u32(&h.counts)?,
            self.read_u32(&h.starts)?,
            self.read_u32(&h.sorted)?,
        ))
    }

    /// Uploads bucket starts and sorted indices (so `self_collide` can be compared alone).
    pub fn set_hash(&mut self, starts: &[u32], sorted: &[u32]) {
        if let Some(h) = &self.hash {
            self.ctx
                .queue
                .write_buffer(&h.starts, 0, bytemuck::cast_slice(starts));
            self.ctx
                .queue
                .write_buffer(&h.sorted, 0, bytemuck::cast_slice(sorted));
        }
    }

    pub(super) fn read_u32(&self, buffer: &wgpu::Buffer) -> Result<Vec<u32>, Error> {
        let size = buffer.size();
        let staging = self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("hash staging"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
        self.ctx.queue.submit([encoder.finish()]);
        let slice = staging.slice(..);
        self.ctx
            .map_read(slice, |bytes| bytemuck::cast_slice(bytes).to_vec())
    }

    /// Reads back the forces the last force stage wrote (for per-stage parity tests).
    pub fn forces(&mut self) -> Result<Vec<Vec4>, Error> {
        Ok(self.read_back(&[&self.forces[self.last_forces]])?.remove(0))
    }

    /// Reads back the forces `hinge_forces` wrote, four per hinge (for per-stage parity tests).
    pub fn hinge_forces(&self) -> Result<Vec<Vec4>, Error> {
        let h = self
            .hinge_forces
            .as_ref()
            .ok_or_else(|| Error::Gpu("hinge_forces is not in the plan".into()))?;
        let staging = self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("hinge_forces staging"),
            size: h.padded_bytes(),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        h.copy_to_buffer(&mut encoder, &staging, 0);
        self.ctx.queue.submit([encoder.finish()]);
        // Back from CSR order (texel k holds ref hinge_refs[k]) to ref order, 4·h + role.
        self.ctx.map_read(staging.slice(..), |bytes| {
            let texels: &[Vec4] = bytemuck::cast_slice(bytes);
            let mut forces = vec![Vec4::ZERO; self.hinge_refs.len()];
            for (k, &r) in self.hinge_refs.iter().enumerate() {
                forces[r as usize] = texels[k];
            }
            forces
        })
    }

    pub(super) fn read_back(&self, arrays: &[&TexelArray]) -> Result<Vec<Vec<Vec4>>, Error> {
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        let mut at = 0;
        for a in arrays {
            a.copy_to_buffer(&mut encoder, &self.staging, at);
            at += a.padded_bytes();
        }
        self.ctx.queue.submit([encoder.finish()]);
        self.ctx.map_read(self.staging.slice(..at), |bytes| {
            let all: &[Vec4] = bytemuck::cast_slice(bytes);
            let mut start = 0;
            arrays
                .iter()
                .map(|a| {
                    let texels = a.padded_bytes() as usize / 16;
                    let data = all[start..start + self.n].to_vec();
                    start += texels;
                    data
                })
                .collect()
        })
    }
}
