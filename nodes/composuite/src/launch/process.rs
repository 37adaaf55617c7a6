//! The launcher's child processes one by one: what a child sets up between fork and exec,
//! signals, how a death is described, and stopping them in order (SIGINT, then SIGKILL).

use std::process::{Child, ExitStatus};
use std::time::{Duration, Instant};

/// How long nodes get to exit after SIGINT before they are killed.
const GRACE: Duration = Duration::from_secs(5);
/// With a recorder: how long the environments keep running after the last command before they
/// are stopped, so reliable DDS can resend whatever the recorder missed (RustDDS heartbeats a
/// lagging reader every 100 ms); a node that exits takes its unacknowledged samples with it.
pub(super) const RECORDER_SETTLE: Duration = Duration::from_secs(1);
/// The recorder runs this much nicer than the environments: it is never on the lockstep
/// chain (sim → reward → agent → sim), so on a machine with few cores it should take the CPU
/// only when the chain leaves it idle and catch up then — reliable DDS keeps what it has not
/// acknowledged until it does.
pub(super) const RECORDER_NICENESS: libc::c_int = 10;

pub(super) struct Running {
    /// What it is, for messages: "sim in /env_00", "environments 0..4 of /train".
    pub(super) what: String,
    /// A recorder: never started again (its bag exists), stopped after the environments.
    pub(super) recorder: bool,
    /// Its command line after the executable (it is started again with the same).
    pub(super) argv: Vec<String>,
    pub(super) child: Child,
    /// Times it was started again.
    pub(super) restarts: u32,
    /// When it died, while it waits for its restart.
    pub(super) died_at: Option<Instant>,
    /// Dead for good (a recorder is never restarted: its bag exists).
    pub(super) gone: bool,
}

impl Running {
    /// "sim in /env_00 exited on its own (killed by signal 9)".
    pub(super) fn death(&self, status: ExitStatus) -> String {
        format!("{} exited on its own ({})", self.what, describe(status))
    }
}

/// What a node process does between fork and exec:
/// - its own process group, so a Ctrl-C at the terminal reaches only the launcher, which stops
///   the nodes in order (the environments, then the recorder, which records until they are
///   gone) instead of all at once;
/// - SIGTERM when the launcher dies, however it dies (even SIGKILL): the node then shuts down
///   as on any SIGTERM — a recorder closes its bag — instead of running on, orphaned. (Linux
///   sends it when the *thread* that spawned the node ends: the suite spawns from the main
///   thread only.)
/// - the recorder at a lower priority, set before the node starts any thread so that it holds
///   for all of them: it is never on the lockstep chain and catches up in the chain's gaps.
///
/// # Safety
/// Only async-signal-safe calls: it runs in the forked child of a multi-threaded process.
pub(super) unsafe fn node_process_setup(
    niceness: libc::c_int,
    launcher: libc::pid_t,
) -> std::io::Result<()> {
    let failed = || Err(std::io::Error::last_os_error());
    // SAFETY: plain system calls on the calling process; no memory is shared or allocated.
    unsafe {
        if libc::setpgid(0, 0) != 0 {
            return failed();
        }
        if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGTERM) != 0 {
            return failed();
        }
        // The launcher may have died between fork and prctl: then no SIGTERM will come.
        if libc::getppid() != launcher {
            return Err(std::io::Error::from_raw_os_error(libc::ESRCH));
        }
        if niceness != 0 {
            let now = libc::getpriority(libc::PRIO_PROCESS, 0);
            if libc::setpriority(libc::PRIO_PROCESS, 0, now + niceness) != 0 {
                return failed();
            }
        }
    }
    Ok(())
}

/// Send `signal` to a child (it may have exited already; that is fine).
fn signal(child: &Child, signal: i32) {
    // SAFETY: kill(2) on a pid we spawned; no memory is touched.
    unsafe {
        libc::kill(child.id() as libc::pid_t, signal);
    }
}

fn describe(status: ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt;
    match (status.code(), status.signal()) {
        (Some(code), _) => format!("exit code {code}"),
        (None, Some(sig)) => format!("killed by signal {sig}"),
        _ => "unknown status".into(),
    }
}

/// SIGINT to every node still running, wait up to [`GRACE`], SIGKILL the rest. True when all
/// exited with code 0. (A node waiting for its restart is dead already, and was reported.)
pub(super) fn stop_all(nodes: &mut [Running]) -> bool {
    // The environments first, then the recorder: it records until they are gone.
    let (recorders, environments): (Vec<&mut Running>, Vec<&mut Running>) = nodes
        .iter_mut()
        .filter(|n| n.died_at.is_none())
        .partition(|n| n.recorder);
    if !recorders.is_empty() && !environments.is_empty() {
        std::thread::sleep(RECORDER_SETTLE);
    }
    let clean = stop_group(environments);
    stop_group(recorders) && clean
}

fn stop_group(mut nodes: Vec<&mut Running>) -> bool {
    for n in nodes.iter() {
        signal(&n.child, libc::SIGINT);
    }
    let until = Instant::now() + GRACE;
    let mut clean = true;
    for n in nodes.iter_mut() {
        let status = loop {
            match n.child.try_wait() {
                Ok(Some(status)) => break Some(status),
                Ok(None) if Instant::now() < until => std::thread::sleep(Duration::from_millis(20)),
                _ => break None,
            }
        };
        match status {
            Some(s) if s.success() => {}
            Some(s) => {
                clean = false;
                eprintln!("composuite launch: {}: {}", n.what, describe(s));
            }
            None => {
                clean = false;
                eprintln!(
                    "composuite launch: {} did not stop within {:?}; killing it",
                    n.what, GRACE
                );
                signal(&n.child, libc::SIGKILL);
                let _ = n.child.wait();
            }
        }
    }
    clean
}
