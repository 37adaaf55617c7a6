//! The command lines of the launcher's children: each environment's namespace, a node's
//! `node KIND --ros-args ...`, and the `launch --env-range` of a process holding a share of the
//! composed environments.

use std::ops::Range;

use composuite_ros::nodes::NodeKind;

use super::LaunchArgs;

/// The namespace of environment `index` of `count`.
pub(super) fn env_namespace(base: &str, index: usize, count: usize) -> String {
    let base = base.trim_end_matches('/');
    if count == 1 {
        if base.is_empty() {
            "/".into()
        } else {
            base.into()
        }
    } else {
        format!("{base}/env_{index:02}")
    }
}

/// A node's command line after the executable: `node KIND --ros-args ...`.
pub(super) fn node_argv(
    kind: NodeKind,
    args: &LaunchArgs,
    namespace: &str,
    index: usize,
) -> Vec<String> {
    let mut argv = vec!["node".to_string(), kind.name().to_string()];
    argv.extend(node_arguments(args, kind, namespace, index));
    argv
}

/// `envs` environments in `processes` contiguous shares, the larger ones first.
pub(super) fn split_environments(envs: usize, processes: usize) -> Vec<Range<usize>> {
    let (share, larger) = (envs / processes, envs % processes);
    let mut start = 0;
    (0..processes)
        .map(|k| {
            let end = start + share + usize::from(k < larger);
            let range = start..end;
            start = end;
            range
        })
        .collect()
}

/// The `--ros-args` of one node.
pub(super) fn node_arguments(
    args: &LaunchArgs,
    kind: NodeKind,
    namespace: &str,
    index: usize,
) -> Vec<String> {
    let mut out = vec![
        "--ros-args".to_string(),
        "-r".into(),
        format!("__ns:={namespace}"),
    ];
    if let Some(file) = &args.params_file {
        out.extend(["--params-file".into(), file.display().to_string()]);
    }
    let mut param = |name: &str, value: String| {
        out.extend(["-p".into(), format!("{name}:={value}")]);
    };
    // Only what was asked for: anything else comes from the params file or the defaults.
    if let Some(mapping) = &args.service_mapping {
        param("service_mapping", mapping.clone());
    }
    match kind {
        NodeKind::Sim => {
            if let Some(mode) = &args.mode {
                param("mode", mode.clone());
            }
        }
        NodeKind::TaskManager => {
            if let Some(task) = &args.task {
                param("task", task.clone());
            }
            if args.seed.is_some() || index > 0 {
                param("seed", (args.seed.unwrap_or(0) + index as u64).to_string());
            }
            if let Some(horizon) = args.horizon {
                param("horizon", horizon.to_string());
            }
            if args.auto_reset {
                param("auto_reset", "true".into());
            }
        }
        NodeKind::Reward => {
            if args.sparse_rewards {
                param("reward_shaping", "false".into());
            }
            if let Some(scale) = args.reward_scale {
                param("reward_scale", format!("{scale:?}"));
            }
        }
        NodeKind::Recorder => {
            if let Some(dir) = &args.record {
                param("output", dir.display().to_string());
            }
            match &args.record_regex {
                Some(r) => param("regex", r.clone()),
                None => param("all", "true".into()),
            }
            if let Some(r) = &args.record_exclude {
                param("exclude_regex", r.clone());
            }
            if let Some(size) = args.record_max_bag_size {
                param("max_bag_size", size.to_string());
            }
            if let Some(seconds) = args.record_max_bag_duration {
                param("max_bag_duration", format!("{seconds:?}"));
            }
        }
    }
    out.extend(["--log-level".into(), args.log_level.clone()]);
    if let Some(enclave) = &args.enclave {
        out.extend(["--enclave".into(), enclave.clone()]);
    }
    if let Some(prefix) = &args.node_enclaves {
        let prefix = prefix.trim_end_matches('/');
        out.extend(["--enclave".into(), format!("{prefix}/{}", kind.name())]);
    }
    out
}

impl LaunchArgs {
    /// The command line of a child process holding `range` of the composed environments: the
    /// options every environment's nodes get, and nothing the launcher keeps for itself (the
    /// recorder, --duration, --processes).
    pub(super) fn container_process_argv(&self, range: &Range<usize>) -> Vec<String> {
        let mut argv: Vec<String> = vec![
            "launch".into(),
            "--namespace".into(),
            self.namespace.clone(),
            "--envs".into(),
            self.envs.to_string(),
            "--env-range".into(),
            format!("{}..{}", range.start, range.end),
            "--respawn".into(),
            self.respawn.to_string(),
            "--respawn-delay".into(),
            format!("{:?}", self.respawn_delay),
            "--log-level".into(),
            self.log_level.clone(),
        ];
        let mut option = |flag: &str, value: Option<String>| {
            if let Some(value) = value {
                argv.extend([flag.to_string(), value]);
            }
        };
        option("--task", self.task.clone());
        option("--mode", self.mode.clone());
        option("--threads", self.threads.map(|t| t.to_string()));
        option("--seed", self.seed.map(|s| s.to_string()));
        option("--horizon", self.horizon.map(|h| h.to_string()));
        option(
            "--reward-scale",
            self.reward_scale.map(|r| format!("{r:?}")),
        );
        option("--service-mapping", self.service_mapping.clone());
        option("--enclave", self.enclave.clone());
        option(
            "--params-file",
            self.params_file.as_ref().map(|f| f.display().to_string()),
        );
        if self.sparse_rewards {
            argv.push("--sparse-rewards".into());
        }
        if self.auto_reset {
            argv.push("--auto-reset".into());
        }
        argv
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::launch::parse;

    #[test]
    fn namespaces_per_environment() {
        assert_eq!(env_namespace("/", 0, 1), "/");
        assert_eq!(env_namespace("/train", 0, 1), "/train");
        assert_eq!(env_namespace("/", 3, 4), "/env_03");
        assert_eq!(env_namespace("/train/", 1, 2), "/train/env_01");
    }

    #[test]
    fn environments_split_into_contiguous_shares() {
        assert_eq!(split_environments(8, 2), [0..4, 4..8]);
        assert_eq!(split_environments(7, 3), [0..3, 3..5, 5..7]);
        assert_eq!(split_environments(3, 3), [0..1, 1..2, 2..3]);
        assert_eq!(split_environments(64, 1), vec![Range { start: 0, end: 64 }]);
    }

    // A share's process gives every one of its nodes the arguments the launcher would have.
    #[test]
    fn a_share_process_gives_its_nodes_the_launchers_arguments() {
        let parent = parse(&[
            "--task",
            "Jaco/plate/wall/push",
            "--mode",
            "realtime",
            "--namespace",
            "/train",
            "--envs",
            "5",
            "--processes",
            "2",
            "--threads",
            "3",
            "--seed",
            "7",
            "--horizon",
            "80",
            "--sparse-rewards",
            "--reward-scale",
            "2.5",
            "--service-mapping",
            "cyclone",
            "--auto-reset",
            "--log-level",
            "warn",
            "--respawn",
            "4",
            "--respawn-delay",
            "0.25",
            "--duration",
            "9",
            "--enclave",
            "/composuite/train",
        ]);
        let sim = node_arguments(&parent, NodeKind::Sim, "/train/env_00", 0);
        assert!(
            sim.windows(2)
                .any(|w| w == ["--enclave", "/composuite/train"])
        );
        let own = parse(&["--node-enclaves", "/composuite/"]);
        for kind in [NodeKind::Sim, NodeKind::Reward] {
            let argv = node_arguments(&own, kind, "/", 0);
            let wanted = format!("/composuite/{}", kind.name());
            assert!(argv.windows(2).any(|w| w == ["--enclave", wanted.as_str()]));
        }
        for range in split_environments(parent.envs, parent.processes) {
            let argv = parent.container_process_argv(&range);
            assert_eq!(argv[0], "launch");
            let argv: Vec<&str> = argv[1..].iter().map(String::as_str).collect();
            let child = parse(&argv);
            assert_eq!(child.env_indices(), Ok(range.clone()));
            assert!(child.composed() && child.processes == 1 && child.duration.is_none());
            assert_eq!((child.respawn, child.respawn_delay), (4, 0.25));
            assert_eq!(child.step_threads(), 3);
            assert_eq!(child.enclave.as_deref(), Some("/composuite/train"));
            for index in range {
                let namespace = env_namespace("/train", index, 5);
                for kind in NodeKind::ALL {
                    assert_eq!(
                        node_arguments(&child, kind, &namespace, index),
                        node_arguments(&parent, kind, &namespace, index),
                        "{kind} of environment {index}"
                    );
                }
            }
        }
    }
}
