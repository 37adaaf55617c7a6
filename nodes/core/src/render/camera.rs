//! The reference's cameras, and the pinhole model every frame is taken with.
//!
//! Poses are written as the reference writes them (MuJoCo: a position and a `w x y z`
//! quaternion of a frame that looks along its −z with +y up in the image) and converted once,
//! here, to the ROS optical frame the renderer works in (+x right, +y down, +z forward: MuJoCo's
//! frame turned π about its x axis). Intrinsics follow robosuite's `get_camera_intrinsic_matrix`:
//! square pixels, `f = (H / 2) / tan(fovy / 2)`, principal point at `(W / 2, H / 2)`; pixel
//! `(i, j)` covers `u ∈ [i, i + 1)`, `v ∈ [j, j + 1)`, row 0 at the top.

use std::fmt;

use nalgebra::{Isometry3, Point3, Quaternion, Translation3, UnitQuaternion, Vector3};

use crate::physics::HAND_LINK;

/// What a camera is fixed to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mount {
    /// The world: the arena's cameras.
    World,
    /// A link of the arm (a URDF link name): the camera moves with it.
    Link(&'static str),
}

/// One camera as the reference defines it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraSpec {
    /// The reference's camera name.
    pub name: &'static str,
    /// What the pose is relative to.
    pub mount: Mount,
    /// Position in the mount's frame (m).
    pub position: [f64; 3],
    /// Orientation of MuJoCo's camera frame in the mount's frame, `[w, x, y, z]` as the
    /// reference writes it (normalised when used, as MuJoCo does).
    pub quat_wxyz: [f64; 4],
    /// Vertical field of view (degrees).
    pub fovy_deg: f64,
}

/// The five cameras, in the order errors list them.
///
/// The four arena cameras are the same in all four of CompoSuite's arena files
/// (`composuite/assets/arenas/{pick_place,push,shelf,trashcan}_arena.xml`, commit `1fa36f6`);
/// they set no `fovy`, so MuJoCo's default of 45° applies. `eye_in_hand` is the camera
/// robosuite (≤ 1.4) puts in every arm's `right_hand` body
/// (`robosuite/models/assets/robots/<arm>/robot.xml`), with its own `fovy` of 75°; this
/// project's `right_hand` link is that body's frame. Numbers are copied as the reference
/// writes them (`0.7071`, not 1/√2), so they can be checked against its files.
#[allow(clippy::approx_constant)]
pub const CAMERAS: [CameraSpec; 5] = [
    CameraSpec {
        name: "frontview",
        mount: Mount::World,
        position: [1.6, 0.0, 1.45],
        quat_wxyz: [0.56, 0.43, 0.43, 0.56],
        fovy_deg: 45.0,
    },
    CameraSpec {
        name: "agentview",
        mount: Mount::World,
        position: [0.5, 0.0, 1.35],
        quat_wxyz: [0.653, 0.271, 0.271, 0.653],
        fovy_deg: 45.0,
    },
    CameraSpec {
        name: "birdview",
        mount: Mount::World,
        position: [-0.2, 0.0, 3.0],
        quat_wxyz: [0.7071, 0.0, 0.0, 0.7071],
        fovy_deg: 45.0,
    },
    CameraSpec {
        name: "sideview",
        mount: Mount::World,
        position: [-0.05651774593317116, 1.2761224129427358, 1.4879572214102434],
        quat_wxyz: [
            0.009905065491771751,
            0.006877963156909582,
            0.5912228352893879,
            0.806418094001364,
        ],
        fovy_deg: 45.0,
    },
    CameraSpec {
        name: "eye_in_hand",
        mount: Mount::Link(HAND_LINK),
        position: [0.05, 0.0, 0.0],
        quat_wxyz: [0.0, 0.707108, 0.707108, 0.0],
        fovy_deg: 75.0,
    },
];

/// The camera of that name, or an error listing the valid names.
pub fn camera_spec(name: &str) -> Result<&'static CameraSpec, RenderError> {
    CAMERAS
        .iter()
        .find(|c| c.name == name)
        .ok_or_else(|| RenderError::UnknownCamera(name.to_string()))
}

impl CameraSpec {
    /// The camera's optical frame in its mount's frame.
    pub fn optical_in_mount(&self) -> Isometry3<f64> {
        let [w, x, y, z] = self.quat_wxyz;
        let mujoco = UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z));
        let flip = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI);
        Isometry3::from_parts(
            Translation3::from(Vector3::from(self.position)),
            mujoco * flip,
        )
    }
}

/// A posed pinhole camera: where it is now and what it sees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// The optical frame in the world (+z forward, +x right, +y down in the image).
    pub pose: Isometry3<f64>,
    /// Vertical field of view (degrees).
    pub fovy_deg: f64,
}

impl Camera {
    /// Focal length in pixels for an image `height` pixels tall (square pixels).
    pub fn focal_px(&self, height: u32) -> f64 {
        0.5 * height as f64 / (self.fovy_deg.to_radians() / 2.0).tan()
    }

    /// The intrinsic matrix `[[f, 0, W/2], [0, f, H/2], [0, 0, 1]]`, row-major, as a ROS
    /// `CameraInfo.k` carries it.
    pub fn intrinsics(&self, width: u32, height: u32) -> [f64; 9] {
        let f = self.focal_px(height);
        let (cx, cy) = (width as f64 / 2.0, height as f64 / 2.0);
        [f, 0.0, cx, 0.0, f, cy, 0.0, 0.0, 1.0]
    }

    /// Where a world point lands: `(u, v, depth)` in pixels (continuous, see the module doc)
    /// and metres along the optical axis; `None` behind the camera.
    pub fn project(&self, world: &Point3<f64>, width: u32, height: u32) -> Option<(f64, f64, f64)> {
        let p = self.pose.inverse_transform_point(world);
        if p.z <= 0.0 {
            return None;
        }
        let f = self.focal_px(height);
        Some((
            f * p.x / p.z + width as f64 / 2.0,
            f * p.y / p.z + height as f64 / 2.0,
            p.z,
        ))
    }

    /// The ray through image point `(u, v)`: its direction in the world, scaled so that its
    /// optical-axis component is 1 (a point at depth `d` is `origin + d · direction`).
    pub fn ray(&self, u: f64, v: f64, width: u32, height: u32) -> (Point3<f64>, Vector3<f64>) {
        let f = self.focal_px(height);
        let local = Vector3::new(
            (u - width as f64 / 2.0) / f,
            (v - height as f64 / 2.0) / f,
            1.0,
        );
        (
            Point3::from(self.pose.translation.vector),
            self.pose.rotation * local,
        )
    }
}

/// Why a frame could not be rendered.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RenderError {
    /// No camera has that name.
    UnknownCamera(String),
    /// A width or height of zero, or beyond [`MAX_SIDE`].
    BadSize {
        /// Requested width (pixels).
        width: u32,
        /// Requested height (pixels).
        height: u32,
    },
}

/// The largest width or height a frame may have (pixels).
pub const MAX_SIDE: u32 = 4096;

impl fmt::Display for RenderError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RenderError::UnknownCamera(name) => {
                let valid: Vec<&str> = CAMERAS.iter().map(|c| c.name).collect();
                write!(
                    f,
                    "unknown camera `{name}`; valid cameras: {}",
                    valid.join(", ")
                )
            }
            RenderError::BadSize { width, height } => write!(
                f,
                "bad image size {width}×{height}: width and height must be 1 to {MAX_SIDE} pixels"
            ),
        }
    }
}

impl std::error::Error for RenderError {}
