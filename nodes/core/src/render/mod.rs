//! Cameras and a CPU renderer: RGB, depth and a per-pixel class map of a task's scene, with
//! no GPU, no window and no dependency beyond nalgebra.
//!
//! [`CAMERAS`] holds the reference's five cameras. [`SceneRenderer`] tessellates the scene
//! once — the arena, the object and the goal marker from the same tables the physics is built
//! from, the arm from its URDF model — and each frame poses those meshes from the simulated
//! world and rasterises them ([`Frame`]). [`Env::render`](crate::env::Env::render) is the
//! usual way in; [`StateRenderer`] draws the same scene from a [`SceneState`] alone (joint
//! positions and the object's pose, what an observation carries), for recordings and remote
//! agents. Why a purpose-built rasteriser, and the frame times: `docs/src/rendering.md`.

mod camera;
mod mesh;
mod raster;
mod scene;
mod state;

pub use camera::{CAMERAS, Camera, CameraSpec, MAX_SIDE, Mount, RenderError, camera_spec};
pub use mesh::Mesh;
pub use raster::{BACKGROUND, Frame, NEAR, SceneClass};
pub use scene::{SceneRenderer, posed_camera};
pub use state::{SceneState, StateRenderer};

#[cfg(test)]
mod test;
