//! Checking the arguments of `composuite launch` before anything starts, each refusal saying
//! what is valid.

use composuite_core::TaskSpec;
use composuite_ros::shared::ros_args::is_fully_qualified_name;

use super::LaunchArgs;

pub(super) fn validate(args: &LaunchArgs) -> Result<(), String> {
    if let Some(task) = &args.task {
        task.parse::<TaskSpec>()
            .map_err(|e| format!("--task: {e}"))?;
    }
    if let Some(mode) = &args.mode
        && composuite_ros::sim::Mode::parse(mode).is_none()
    {
        return Err(format!(
            "--mode {mode} is invalid; valid: lockstep, realtime"
        ));
    }
    if let Some(mapping) = &args.service_mapping {
        composuite_ros::shared::node::service_mapping(mapping)
            .map_err(|e| format!("--service-mapping: {e}"))?;
    }
    if !is_fully_qualified_name(&args.namespace) {
        return Err(format!(
            "--namespace {} is invalid; it must be absolute, e.g. /train",
            args.namespace
        ));
    }
    if let Some(enclave) = &args.enclave
        && !is_fully_qualified_name(enclave)
    {
        return Err(format!(
            "--enclave {enclave} is invalid; it must be a fully qualified name, e.g. /composuite/sim"
        ));
    }
    if let Some(prefix) = &args.node_enclaves {
        if !is_fully_qualified_name(prefix) {
            return Err(format!(
                "--node-enclaves {prefix} is invalid; it must be a fully qualified name, e.g. \
                 /composuite"
            ));
        }
        if args.composed() {
            return Err(
                "--node-enclaves needs node processes (one environment, or --isolate): \
                 a composed process is one DDS participant, in one enclave (--enclave)"
                    .into(),
            );
        }
    }
    if !(1..=100).contains(&args.envs) {
        return Err(format!("--envs {} is invalid; valid: 1 to 100", args.envs));
    }
    if !(1..=args.envs).contains(&args.processes) {
        return Err(format!(
            "--processes {} is invalid; valid: 1 to --envs ({})",
            args.processes, args.envs
        ));
    }
    if args.processes > 1 && !args.composed() {
        return Err(
            "--processes needs composed environments: --envs 2 or more, without --isolate".into(),
        );
    }
    args.env_indices()?;
    if args.threads == Some(0) {
        return Err(
            "--threads 0 is invalid; at least 1 thread steps the environments (leave it out \
             for one per available core)"
                .into(),
        );
    }
    if args.threads.is_some() && !args.composed() {
        return Err(
            "--threads needs composed environments: --envs 2 or more, without --isolate (a \
             node process steps its one environment on its own thread)"
                .into(),
        );
    }
    if args.horizon == Some(0) {
        return Err("--horizon must be at least 1".into());
    }
    if let Some(scale) = args.reward_scale
        && !scale.is_finite()
    {
        return Err(format!(
            "--reward-scale {scale} is invalid; a finite number"
        ));
    }
    if let Some(d) = args.duration
        && !(d.is_finite() && d > 0.0)
    {
        return Err(format!("--duration {d} is invalid; seconds > 0"));
    }
    if !(args.respawn_delay.is_finite() && args.respawn_delay >= 0.0) {
        return Err(format!(
            "--respawn-delay {} is invalid; seconds >= 0",
            args.respawn_delay
        ));
    }
    if let Some(dir) = &args.record
        && dir.exists()
    {
        return Err(format!(
            "--record {}: it exists already; give a new directory (a bag is never overwritten)",
            dir.display()
        ));
    }
    if args.record_max_bag_size == Some(0) {
        return Err(
            "--record-max-bag-size 0 is invalid; bytes > 0 (leave it out for one file)".into(),
        );
    }
    if let Some(s) = args.record_max_bag_duration
        && !(s.is_finite() && s > 0.0)
    {
        return Err(format!(
            "--record-max-bag-duration {s} is invalid; seconds > 0 (leave it out for one file)"
        ));
    }
    for (flag, regex) in [
        ("--record-regex", &args.record_regex),
        ("--record-exclude", &args.record_exclude),
    ] {
        if let Some(r) = regex {
            regex::Regex::new(r).map_err(|e| format!("{flag}: not a regex: {e}"))?;
        }
    }
    if let Some(f) = &args.params_file
        && !f.is_file()
    {
        return Err(format!("--params-file {}: no such file", f.display()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::launch::parse;

    #[test]
    fn bad_processes_and_ranges_are_refused_with_what_is_valid() {
        let refused = |argv: &[&str]| validate(&parse(argv)).unwrap_err();
        assert!(refused(&["--envs", "4", "--processes", "5"]).contains("valid: 1 to --envs (4)"));
        assert!(refused(&["--envs", "4", "--processes", "0"]).contains("--processes 0"));
        assert!(
            refused(&["--envs", "4", "--processes", "2", "--isolate"])
                .contains("without --isolate")
        );
        assert!(
            refused(&["--envs", "4", "--env-range", "3..3"]).contains("START < END <= --envs (4)")
        );
        assert!(refused(&["--envs", "4", "--env-range", "2..9"]).contains("--env-range 2..9"));
        assert!(refused(&["--envs", "4", "--env-range", "x"]).contains("START..END"));
        assert!(validate(&parse(&["--envs", "4", "--processes", "4"])).is_ok());
        assert!(refused(&["--envs", "4", "--threads", "0"]).contains("--threads 0 is invalid"));
        assert!(validate(&parse(&["--envs", "4", "--threads", "1"])).is_ok());
        assert!(refused(&["--envs", "4", "--isolate", "--threads", "2"]).contains("composed"));
    }

    #[test]
    fn node_enclaves_need_node_processes_and_a_full_name() {
        let refused = |argv: &[&str]| validate(&parse(argv)).unwrap_err();
        assert!(refused(&["--envs", "2", "--node-enclaves", "/c"]).contains("node processes"));
        assert!(refused(&["--node-enclaves", "c"]).contains("--node-enclaves c is invalid"));
        assert!(validate(&parse(&["--node-enclaves", "/c"])).is_ok());
        assert!(
            validate(&parse(&[
                "--envs",
                "2",
                "--isolate",
                "--node-enclaves",
                "/c"
            ]))
            .is_ok()
        );
    }
}
