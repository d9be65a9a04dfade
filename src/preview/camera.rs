//! Preview cameras: presets that frame a bounding box, or an eye, target and field of view.

use glam::{Mat4, Vec3};
use std::str::FromStr;

/// A perspective camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position in m.
    pub eye: Vec3,
    /// Point looked at in m.
    pub target: Vec3,
    /// Vertical field of view in degrees.
    pub fov_deg: f32,
}

/// Where a preset camera stands, relative to the framed box (+z is the body's front).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraPreset {
    /// In front, looking along −z.
    Front,
    /// Behind, looking along +z.
    Back,
    /// On the +x side.
    Side,
    /// Front-right and a little above.
    ThreeQuarter,
}

impl FromStr for CameraPreset {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "front" => Ok(CameraPreset::Front),
            "back" => Ok(CameraPreset::Back),
            "side" => Ok(CameraPreset::Side),
            "three-quarter" => Ok(CameraPreset::ThreeQuarter),
            _ => Err(format!(
                "unknown camera {s:?}; use front, back, side or three-quarter"
            )),
        }
    }
}

/// The presets' field of view in degrees.
pub const PRESET_FOV_DEG: f32 = 30.0;

impl CameraPreset {
    fn direction(self) -> Vec3 {
        match self {
            CameraPreset::Front => Vec3::Z,
            CameraPreset::Back => -Vec3::Z,
            CameraPreset::Side => Vec3::X,
            CameraPreset::ThreeQuarter => Vec3::new(0.7, 0.25, 0.7).normalize(),
        }
    }

    /// A camera that sees the whole box `lo..hi` at aspect ratio `aspect` (width / height),
    /// looking at its centre from the preset's direction, as close as it can while every
    /// corner stays inside the middle 1/1.1 of the image (a 10% margin at the tightest side).
    pub fn framing(self, lo: Vec3, hi: Vec3, aspect: f32) -> Camera {
        let center = 0.5 * (lo + hi);
        let dir = self.direction();
        // The view's axes, as `look_at` builds them with +y up.
        let right = (-dir).cross(Vec3::Y).normalize();
        let up = right.cross(-dir);
        let tan_v = (0.5 * PRESET_FOV_DEG).to_radians().tan() / 1.1;
        let tan_h = tan_v * aspect;
        let mut distance: f32 = 1e-3;
        for k in 0..8 {
            let corner = Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            ) - center;
            // A corner `toward` the camera from the centre needs the eye that much further.
            let toward = corner.dot(dir);
            distance = distance
                .max(toward + corner.dot(right).abs() / tan_h)
                .max(toward + corner.dot(up).abs() / tan_v);
        }
        Camera {
            eye: center + distance * dir,
            target: center,
            fov_deg: PRESET_FOV_DEG,
        }
    }
}

impl Camera {
    /// Projection × view, with wgpu's [0, 1] depth range.
    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        let distance = (self.eye - self.target).length().max(1e-3);
        let view = glam::camera::rh::view::look_at_mat4(self.eye, self.target, Vec3::Y);
        let proj = glam::camera::rh::proj::directx::perspective(
            self.fov_deg.to_radians(),
            aspect,
            0.01 * distance,
            100.0 * distance,
        );
        proj * view
    }
}

/// A preset that frames the cloth, or a fixed camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CameraChoice {
    /// Frames the cloth's bounding box.
    Preset(CameraPreset),
    /// Fixed eye, target and field of view.
    Custom(Camera),
}

impl CameraChoice {
    /// The camera for a cloth inside `lo..hi` at aspect ratio `aspect`.
    pub fn camera(self, lo: Vec3, hi: Vec3, aspect: f32) -> Camera {
        match self {
            CameraChoice::Preset(p) => p.framing(lo, hi, aspect),
            CameraChoice::Custom(c) => c,
        }
    }
}
