//! The sim's cameras on ROS: for each camera the `cameras` parameter names (none by default),
//! `camera/<name>/image_raw` (`sensor_msgs/Image`, `rgb8`) and `camera/<name>/camera_info`
//! (`sensor_msgs/CameraInfo`) after every step and reset, stamped with the sim time of the step
//! they show (the observation's stamp), in the frame `<name>_optical_frame`.
//!
//! Frames come from the core's renderer ([`Env::render`]); nothing about drawing lives here.
//! The intrinsics are the camera table's pinhole (`f = (H / 2) / tan(fovy / 2)`, principal
//! point `(W / 2, H / 2)`, square pixels), with `plumb_bob` and zero distortion as Gazebo
//! publishes a perfect simulated camera. The optical frames go out on `tf_static`: the arena's
//! cameras in `world`, `eye_in_hand` in the hand link it is mounted on.

use composuite_core::env::Env;
use composuite_core::render::{Mount, camera_spec};
use composuite_msgs::builtin_interfaces::msg::Time;
use composuite_msgs::geometry_msgs::msg::TransformStamped;
use composuite_msgs::sensor_msgs::msg::{CameraInfo, Image, RegionOfInterest};
use composuite_msgs::std_msgs::msg::Header;
use ros2_client::ParameterValue;

use crate::shared::intra_process::Publisher;
use crate::shared::names::WORLD_FRAME;
use crate::shared::node::{RosNode, StartError};
use crate::shared::qos;
use crate::sim::view;

/// Default image width and height (pixels).
pub const DEFAULT_SIZE: i64 = 256;
/// The largest width or height the parameters accept (pixels): the renderer's limit.
pub const MAX_SIZE: i64 = composuite_core::render::MAX_SIDE as i64;

/// Check of the `cameras` parameter: known names, each once.
pub fn check_cameras(v: &ParameterValue) -> Result<(), String> {
    let ParameterValue::StringArray(names) = v else {
        return Err("a list of camera names".into());
    };
    for (i, name) in names.iter().enumerate() {
        camera_spec(name).map_err(|e| e.to_string())?;
        if names[..i].contains(name) {
            return Err(format!("camera `{name}` is listed twice"));
        }
    }
    Ok(())
}

/// Check of `camera_width` / `camera_height`.
pub fn check_size(v: &ParameterValue) -> Result<(), String> {
    match v {
        ParameterValue::Integer(n) if (1..=MAX_SIZE).contains(n) => Ok(()),
        _ => Err(format!("pixels, 1 to {MAX_SIZE}")),
    }
}

/// `camera/<name>/image_raw`.
pub fn image_topic(camera: &str) -> String {
    format!("camera/{camera}/image_raw")
}

/// `camera/<name>/camera_info`.
pub fn info_topic(camera: &str) -> String {
    format!("camera/{camera}/camera_info")
}

/// The tf frame images of `camera` are in.
pub fn optical_frame(camera: &str) -> String {
    format!("{camera}_optical_frame")
}

struct CameraOut {
    name: &'static str,
    image: Publisher<Image>,
    info: Publisher<CameraInfo>,
}

/// The enabled cameras' publishers and their image size.
pub struct Cameras {
    out: Vec<CameraOut>,
    width: u32,
    height: u32,
}

impl Cameras {
    /// Publishers for the cameras the node's `cameras` parameter names (already checked), at
    /// `camera_width` × `camera_height`.
    pub fn new(node: &mut RosNode) -> Result<Cameras, StartError> {
        let names = match node.param("cameras") {
            ParameterValue::StringArray(names) => names,
            _ => Vec::new(),
        };
        let mut out = Vec::new();
        for name in names {
            let spec = camera_spec(&name).map_err(|e| StartError(e.to_string()))?;
            // Reliable, as every state topic: a reliable writer serves best-effort readers
            // (rclpy's sensor-data profile) as well as reliable ones (the recorder).
            out.push(CameraOut {
                name: spec.name,
                image: node.publisher(&image_topic(spec.name), qos::state())?,
                info: node.publisher(&info_topic(spec.name), qos::state())?,
            });
        }
        let side = |name| node.param_i64(name).clamp(1, MAX_SIZE) as u32;
        Ok(Cameras {
            out,
            width: side("camera_width"),
            height: side("camera_height"),
        })
    }

    /// The enabled cameras' names, for the log.
    pub fn names(&self) -> Vec<&'static str> {
        self.out.iter().map(|c| c.name).collect()
    }

    /// The optical frames of the enabled cameras, for `tf_static`.
    pub fn static_transforms(&self, stamp: &Time) -> Vec<TransformStamped> {
        self.out
            .iter()
            .map(|c| {
                let spec = camera_spec(c.name).expect("checked when made");
                let parent = match spec.mount {
                    Mount::World => WORLD_FRAME,
                    Mount::Link(link) => link,
                };
                view::transform_stamped(
                    parent,
                    &optical_frame(c.name),
                    &spec.optical_in_mount(),
                    stamp.clone(),
                )
            })
            .collect()
    }

    /// Render every enabled camera's view of `env` now and publish it, stamped `stamp`.
    pub fn publish(&self, env: &mut Env, stamp: &Time) {
        for c in &self.out {
            // Names and sizes were checked when the cameras were made: neither call can fail.
            let (Ok(frame), Ok(camera)) = (
                env.render(c.name, self.width, self.height),
                env.camera(c.name),
            ) else {
                continue;
            };
            let header = Header {
                stamp: stamp.clone(),
                frame_id: optical_frame(c.name),
            };
            // Publishing only fails when DDS is shutting down; the next step tries again.
            let _ = c.image.publish(Image {
                header: header.clone(),
                height: frame.height,
                width: frame.width,
                encoding: "rgb8".into(),
                is_bigendian: 0,
                step: 3 * frame.width,
                data: frame.rgb,
            });
            let _ = c.info.publish(camera_info(
                header,
                self.width,
                self.height,
                camera.intrinsics(self.width, self.height),
            ));
        }
    }
}

/// A perfect pinhole's `CameraInfo`: intrinsics `k`, no distortion, identity rectification,
/// `p = [k | 0]` (a monocular camera), full-image region of interest.
pub fn camera_info(header: Header, width: u32, height: u32, k: [f64; 9]) -> CameraInfo {
    CameraInfo {
        header,
        height,
        width,
        distortion_model: "plumb_bob".into(),
        d: vec![0.0; 5],
        k,
        r: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        p: [
            k[0], k[1], k[2], 0.0, k[3], k[4], k[5], 0.0, k[6], k[7], k[8], 0.0,
        ],
        binning_x: 0,
        binning_y: 0,
        roi: RegionOfInterest {
            x_offset: 0,
            y_offset: 0,
            height: 0,
            width: 0,
            do_rectify: false,
        },
    }
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn unknown_or_repeated_cameras_are_refused_naming_the_valid_ones() {
        let list = |names: &[&str]| {
            ParameterValue::StringArray(names.iter().map(|s| s.to_string()).collect())
        };
        assert!(check_cameras(&list(&[])).is_ok());
        assert!(check_cameras(&list(&["frontview", "eye_in_hand"])).is_ok());
        let err = check_cameras(&list(&["frontview", "front"])).unwrap_err();
        assert!(
            err.contains("`front`")
                && err.contains("frontview, agentview, birdview, sideview, eye_in_hand"),
            "{err}"
        );
        assert!(
            check_cameras(&list(&["birdview", "birdview"]))
                .unwrap_err()
                .contains("twice")
        );
        assert!(check_size(&ParameterValue::Integer(0)).is_err());
        assert!(check_size(&ParameterValue::Integer(MAX_SIZE + 1)).is_err());
        assert!(check_size(&ParameterValue::Integer(84)).is_ok());
    }

    #[test]
    fn the_parameters_description_names_every_camera() {
        let spec = crate::sim::PARAMS
            .iter()
            .find(|p| p.name == "cameras")
            .unwrap();
        for camera in composuite_core::render::CAMERAS {
            assert!(spec.description.contains(camera.name), "{}", camera.name);
        }
    }

    #[test]
    fn camera_info_is_the_pinhole_of_the_camera_table() {
        let mut env = Env::new(
            "IIWA/box/no_obstacle/pick_place".parse().unwrap(),
            Default::default(),
        );
        env.reset(0).unwrap();
        let k = env.camera("frontview").unwrap().intrinsics(640, 480);
        let info = camera_info(Header::default(), 640, 480, k);
        // fovy 45°: f = 240 / tan(22.5°)
        assert!((info.k[0] - 579.411).abs() < 1e-3 && info.k[0] == info.k[4]);
        assert_eq!((info.k[2], info.k[5]), (320.0, 240.0));
        assert_eq!(info.p[0..3], info.k[0..3]);
        assert_eq!(info.p[3], 0.0);
        assert_eq!(info.d, vec![0.0; 5]);
        assert_eq!(info.r[0] + info.r[4] + info.r[8], 3.0);
    }
}
