//! `composuite bag play`: a bag published into a running graph again (the player itself is
//! `composuite_ros::player`), with progress on stderr and a summary at the end.

use std::path::Path;
use std::time::{Duration, Instant};

use composuite_msgs::rosgraph_msgs::msg::Clock;
use composuite_ros::player::{PlayOptions, PlayProgress, parse_remap, play};
use composuite_ros::shared::convert::time_from_nanos;
use composuite_ros::shared::names;
use composuite_ros::shared::node::{NodeSpec, RosNode, Startup, shutdown_signal};
use composuite_ros::shared::qos;

const PLAYER: NodeSpec = NodeSpec {
    name: "bag_player",
    binary: "composuite bag play",
    about: "plays a bag back into a running graph",
    params: &[],
};

/// Run `composuite bag play`.
pub fn run(
    bag: &Path,
    rate: f64,
    topics: &[String],
    clock_hz: Option<f64>,
    remaps: &[String],
    delay: f64,
) -> Result<(), String> {
    if !(delay.is_finite() && delay >= 0.0) {
        return Err(format!("--delay {delay} is invalid: seconds >= 0"));
    }
    let options = PlayOptions {
        rate,
        topics: topics.to_vec(),
        clock_hz,
        remaps: remaps
            .iter()
            .map(|r| parse_remap(r))
            .collect::<Result<_, _>>()?,
        delay: Duration::from_secs_f64(delay),
    };
    let mut node = match RosNode::start(&PLAYER, &[]).map_err(|e| e.to_string())? {
        Startup::Node(node) => node,
        Startup::Help(_) => unreachable!("no --help given"),
    };
    let clock = node
        .publisher::<Clock>(names::CLOCK, qos::clock())
        .map_err(|e| e.to_string())?;
    let mut publish_clock = |ns: u64| {
        let _ = clock.publish(Clock {
            clock: time_from_nanos(ns),
        });
    };
    let signals = shutdown_signal().map_err(|e| format!("cannot watch for signals: {e}"))?;
    let stop = || signals.try_recv().is_ok();
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:30} {pos}/{len} messages  bag time {msg}  [{elapsed_precise}]",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut last_line = Instant::now();
    let show = |p: PlayProgress| {
        bar.set_length(p.total);
        bar.set_position(p.published);
        bar.set_message(format!("{:.1} s", p.bag_time.as_secs_f64()));
        // Not a terminal (a log file, CI): a line a second instead of a bar.
        if bar.is_hidden() && last_line.elapsed() >= Duration::from_secs(1) {
            last_line = Instant::now();
            eprintln!(
                "played {}/{} messages, bag time {:.1} s",
                p.published,
                p.total,
                p.bag_time.as_secs_f64()
            );
        }
    };
    let participant = node.context.domain_participant();
    let clock_sink: Option<&mut dyn FnMut(u64)> = if clock_hz.is_some() {
        Some(&mut publish_clock)
    } else {
        None
    };
    let report = play(&participant, bag, &options, clock_sink, &stop, show);
    bar.finish_and_clear();
    let report = report?;
    let published: u64 = report.published.values().sum();
    println!(
        "{} {published} messages on {} topics{}: {:.2} s of bag time in {:.2} s (rate {rate})",
        if report.interrupted {
            "interrupted after"
        } else {
            "played"
        },
        report.published.len(),
        if clock_hz.is_some() {
            format!(" and {} /clock ticks", report.clock_ticks)
        } else {
            String::new()
        },
        report.bag_span.as_secs_f64(),
        report.wall.as_secs_f64(),
    );
    for (topic, count) in &report.published {
        println!("  {topic}: {count}");
    }
    node.shutdown();
    Ok(())
}
