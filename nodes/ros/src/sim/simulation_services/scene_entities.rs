//! The scene's entities as the standard sees them: listing and filtering them, their info,
//! state and bounds, and setting the object's state.

use composuite_msgs::geometry_msgs::msg::{Twist, Vector3};
use composuite_msgs::simulation_interfaces::msg::{Bounds, EntityState, Result as SimResult};
use composuite_msgs::simulation_interfaces::srv;

use crate::shared::convert;
use crate::shared::names;
use crate::shared::node::Logger;
use crate::sim::Sim;
use crate::simulation_interfaces::entities::{self, Entity, Kind};
use crate::simulation_interfaces::{self as si, failed, ok};

fn vector(v: &nalgebra::Vector3<f64>) -> Vector3 {
    Vector3 {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

impl Sim {
    /// The current scene's entities (none before the first scene).
    fn entity_list(&self) -> Vec<Entity> {
        self.run
            .as_ref()
            .map(|run| entities::entities(run.env.task()))
            .unwrap_or_default()
    }

    /// The entity named `name`, or RESULT_NOT_FOUND naming the valid ones.
    pub(super) fn entity(&self, name: &str) -> Result<Entity, SimResult> {
        if self.run.is_none() {
            return Err(failed(
                SimResult::RESULT_INCORRECT_STATE,
                "no world yet (the task manager publishes the scene)",
            ));
        }
        let mut list = self.entity_list();
        entities::find(&list, name)
            .map(|i| list.swap_remove(i))
            .map_err(|why| failed(SimResult::RESULT_NOT_FOUND, why))
    }

    /// The entities passing `filters` (name regex, categories, tags); bounds filters are not
    /// offered.
    pub(super) fn filtered(
        &self,
        filters: &composuite_msgs::simulation_interfaces::msg::EntityFilters,
    ) -> Result<Vec<Entity>, SimResult> {
        if filters.bounds.r#type != Bounds::TYPE_EMPTY {
            return Err(failed(
                SimResult::RESULT_FEATURE_UNSUPPORTED,
                "filtering by bounds is not offered; leave `bounds` empty (TYPE_EMPTY) and \
                 filter by name, category or tags",
            ));
        }
        let regex = if filters.filter.is_empty() {
            None
        } else {
            Some(regex::Regex::new(&filters.filter).map_err(|e| {
                failed(
                    SimResult::RESULT_OPERATION_FAILED,
                    format!(
                        "filter `{}` is not a valid regular expression: {e}",
                        filters.filter
                    ),
                )
            })?)
        };
        Ok(self
            .entity_list()
            .into_iter()
            .filter(|e| regex.as_ref().is_none_or(|r| r.is_match(e.name)))
            .filter(|e| {
                filters.categories.is_empty()
                    || filters
                        .categories
                        .iter()
                        .any(|c| c.category == e.category())
            })
            .filter(|e| si::tags_match(&filters.tags, &e.tags))
            .collect())
    }

    /// An entity's pose and twist in `world`, stamped with the sim time. The acceleration is
    /// not measured: zero.
    pub(super) fn entity_state(&self, entity: &Entity) -> EntityState {
        let run = self.run.as_ref().expect("entities exist only with a run");
        let (pose, linear, angular) = entity.motion(&run.env);
        let mut header = convert::header(convert::time_from_nanos(self.sim_time_ns));
        header.frame_id = names::WORLD_FRAME.into();
        EntityState {
            header,
            pose: convert::pose(&pose),
            twist: Twist {
                linear: vector(&linear),
                angular: vector(&angular),
            },
            acceleration: Default::default(),
        }
    }

    pub(super) fn set_entity_state(
        &mut self,
        req: &srv::SetEntityStateRequest,
        log: &Logger,
    ) -> SimResult {
        use srv::SetEntityStateResponse as R;
        let entity = match self.entity(&req.entity) {
            Ok(e) => e,
            Err(result) => return result,
        };
        match entity.kind {
            Kind::Object => {}
            Kind::Robot => {
                return failed(
                    SimResult::RESULT_OPERATION_FAILED,
                    "the robot's base is fixed and its joints move it (joint_command, \
                     reference_action, the controllers); only `object` can be set",
                );
            }
            Kind::Static => {
                return failed(
                    SimResult::RESULT_OPERATION_FAILED,
                    format!(
                        "`{}` is a static part of the task's arena; only `object` can be set",
                        entity.name
                    ),
                );
            }
        }
        let frame = req.state.header.frame_id.as_str();
        if !frame.is_empty() && frame != names::WORLD_FRAME {
            return failed(
                R::INVALID_POSE,
                format!(
                    "frame `{frame}` is not known here; give the state in `world` (or leave frame_id empty)"
                ),
            );
        }
        let p = &req.state.pose;
        let q = &p.orientation;
        let norm = (q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w).sqrt();
        if !norm.is_finite() || (norm - 1.0).abs() > 1e-3 {
            return failed(
                R::INVALID_POSE,
                format!(
                    "the orientation ({}, {}, {}, {}) has length {norm}; a rotation quaternion has length 1",
                    q.x, q.y, q.z, q.w
                ),
            );
        }
        let pose = nalgebra::Isometry3::from_parts(
            nalgebra::Translation3::new(p.position.x, p.position.y, p.position.z),
            nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                q.w, q.x, q.y, q.z,
            )),
        );
        let v = |v: &Vector3| nalgebra::Vector3::new(v.x, v.y, v.z);
        let run = self.run.as_mut().expect("checked by entity()");
        match run.env.set_object_state(
            &pose,
            &v(&req.state.twist.linear),
            &v(&req.state.twist.angular),
        ) {
            Ok(()) => {
                log.info(format!(
                    "{}: object at ({:.3}, {:.3}, {:.3}) m; the next step's observation and reward follow",
                    names::SET_ENTITY_STATE,
                    p.position.x,
                    p.position.y,
                    p.position.z
                ));
                let a = &req.state.acceleration;
                if [
                    a.linear.x,
                    a.linear.y,
                    a.linear.z,
                    a.angular.x,
                    a.angular.y,
                    a.angular.z,
                ]
                .iter()
                .any(|x| *x != 0.0)
                {
                    return failed(
                        SimResult::RESULT_OK,
                        "pose and twist set; the acceleration is not settable (the physics \
                         integrates forces) and was ignored",
                    );
                }
                ok()
            }
            Err(why) => failed(R::INVALID_POSE, why),
        }
    }
}

/// An entity's bounds as a `TYPE_BOX` (two opposite corners in its body frame), or why none.
pub(super) fn entity_bounds(entity: &Entity) -> Result<Bounds, SimResult> {
    let Some((lo, hi)) = entity.bounds() else {
        return Err(failed(
            SimResult::RESULT_OPERATION_FAILED,
            format!(
                "`{}` has no fixed bounds: the arm's extent changes with its joints (its links \
                 are on `tf`)",
                entity.name
            ),
        ));
    };
    Ok(Bounds {
        r#type: Bounds::TYPE_BOX,
        points: vec![vector(&lo.coords), vector(&hi.coords)],
    })
}
