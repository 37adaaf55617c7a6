//! The DDS library's own log records (RustDDS and ros2-client use the `log` crate) on stderr,
//! in the nodes' line format, so a discovery or transport problem leaves a trace.
//!
//! Each line names the participant's owner (the node, or the container of composed nodes), since
//! the nodes of one launch usually share one log, and is written with one `write` call, so lines
//! of processes writing to the same file do not interleave.
//!
//! The level comes from `COMPOSUITE_DDS_LOG` (`off`, `error`, `warn`, `info`, `debug`,
//! `trace`; default `error`): RustDDS is chatty at `info` and below, so raise it only to
//! investigate.

use std::io::Write;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{SystemTime, UNIX_EPOCH};

/// The environment variable that sets the DDS log level.
pub const DDS_LOG_VAR: &str = "COMPOSUITE_DDS_LOG";

struct StderrLog;

impl log::Log for StderrLog {
    fn enabled(&self, metadata: &log::Metadata) -> bool {
        metadata.level() <= log::max_level()
    }

    fn log(&self, record: &log::Record) {
        if !self.enabled(record.metadata()) {
            return;
        }
        if log::max_level() < log::LevelFilter::Debug && key_exchange_noise(record) {
            // Once, what they are; each one only at debug.
            if !EXPLAINED.swap(true, Ordering::Relaxed) {
                print_line(
                    log::Level::Warn,
                    record.target(),
                    &format_args!(
                        "secured messages that met an endpoint whose keys had not arrived yet \
                         could not be encoded or decoded and were dropped (normal while \
                         participants exchange keys after discovery; reliable ones are sent \
                         again); {DDS_LOG_VAR}=debug shows each"
                    ),
                );
            }
            return;
        }
        print_line(record.level(), record.target(), record.args());
    }

    fn flush(&self) {}
}

/// Whether the key-exchange explanation was printed.
static EXPLAINED: AtomicBool = AtomicBool::new(false);

/// Who owns this process's participant, as its lines name it (set once, by `install`).
static OWNER: OnceLock<String> = OnceLock::new();

fn print_line(level: log::Level, target: &str, text: &std::fmt::Arguments<'_>) {
    let now = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap_or_default();
    let owner = OWNER.get().map(String::as_str).unwrap_or("?");
    write_stderr_line(&line(level, now, owner, target, text));
}

/// One record as a line: `[LEVEL] [wall time] [dds OWNER TARGET]: text`.
fn line(
    level: log::Level,
    now: std::time::Duration,
    owner: &str,
    target: &str,
    text: &std::fmt::Arguments<'_>,
) -> String {
    format!(
        "[{level}] [{}.{:09}] [dds {owner} {target}]: {text}",
        now.as_secs(),
        now.subsec_nanos(),
    )
}

/// `line` and a newline on stderr in one `write` call: stderr is unbuffered, so `eprintln!`
/// writes a formatted line piece by piece, and the pieces of processes sharing one log file
/// interleave mid-line.
pub fn write_stderr_line(line: &str) {
    let mut bytes = Vec::with_capacity(line.len() + 1);
    bytes.extend_from_slice(line.as_bytes());
    bytes.push(b'\n');
    // Nothing sensible to do if stderr is gone.
    let _ = std::io::stderr().lock().write_all(&bytes);
}

/// Whether RustDDS logs `record` (as an error) because a secured message met an endpoint whose
/// crypto keys have not arrived yet: it happens for a moment after every discovery of a
/// secured participant, until the key exchange completes.
fn key_exchange_noise(record: &log::Record) -> bool {
    let target = record.target();
    if !target.starts_with("rustdds::") || record.level() != log::Level::Error {
        return false;
    }
    let text = record.args().to_string();
    text.contains("Could not find a remote EndpointCryptoHandle")
        || (target == "rustdds::rtps::message_receiver"
            && text.starts_with("Submessage decoding failed: SecurityError"))
}

/// The level named by the variable's value (`None` = unset).
pub fn parse_level(value: Option<&str>) -> Result<log::LevelFilter, String> {
    let Some(text) = value.map(str::trim).filter(|t| !t.is_empty()) else {
        return Ok(log::LevelFilter::Error);
    };
    text.parse().map_err(|_| {
        format!("{DDS_LOG_VAR}={text} is invalid; valid: off, error, warn, info, debug, trace")
    })
}

/// Send the `log` crate's records to stderr at `level`, each line naming `owner` (the node or
/// container whose participant this is). Once per process; a second call (a logger already set,
/// e.g. in tests) only changes the level.
pub fn install(level: log::LevelFilter, owner: &str) {
    static LOGGER: StderrLog = StderrLog;
    let _ = OWNER.set(format!("{owner} pid {}", std::process::id()));
    let _ = log::set_logger(&LOGGER);
    log::set_max_level(level);
}

/// No more DDS records (the process is shutting its participant down).
pub fn quiet() {
    log::set_max_level(log::LevelFilter::Off);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_parse_and_bad_values_name_the_valid_ones() {
        assert_eq!(parse_level(None), Ok(log::LevelFilter::Error));
        assert_eq!(parse_level(Some("")), Ok(log::LevelFilter::Error));
        assert_eq!(parse_level(Some("warn")), Ok(log::LevelFilter::Warn));
        assert_eq!(parse_level(Some("DEBUG")), Ok(log::LevelFilter::Debug));
        assert_eq!(parse_level(Some("off")), Ok(log::LevelFilter::Off));
        let err = parse_level(Some("loud")).unwrap_err();
        assert!(
            err.contains("COMPOSUITE_DDS_LOG=loud") && err.contains("trace"),
            "{err}"
        );
    }

    #[test]
    fn a_line_names_the_participant_owner_and_the_source() {
        let at = std::time::Duration::new(17, 5);
        let text = line(
            log::Level::Info,
            at,
            "/env_00/sim pid 42",
            "rustdds::discovery",
            &format_args!("Authenticated {}", 7),
        );
        assert_eq!(
            text,
            "[INFO] [17.000000005] [dds /env_00/sim pid 42 rustdds::discovery]: Authenticated 7"
        );
    }

    #[test]
    fn only_the_key_exchange_errors_count_as_its_noise() {
        let check = |target: &str, level: log::Level, text: &str| {
            key_exchange_noise(
                &log::Record::builder()
                    .target(target)
                    .level(level)
                    .args(format_args!("{text}"))
                    .build(),
            )
        };
        let receiver = "rustdds::rtps::message_receiver";
        let decode = "Submessage decoding failed: SecurityError { msg: \"ring\" }";
        assert!(check(receiver, log::Level::Error, decode));
        assert!(check(
            "rustdds::rtps::writer",
            log::Level::Error,
            "Failed to send message to readers. Encoding failed: SecurityError { msg: \"Could \
             not find a remote EndpointCryptoHandle for the pair\" }"
        ));
        assert!(!check(receiver, log::Level::Warn, decode));
        assert!(!check("rustdds::rtps::reader", log::Level::Error, decode));
        assert!(!check(
            receiver,
            log::Level::Error,
            "Submessage decoding failed: Io"
        ));
        assert!(!check(
            "composuite",
            log::Level::Error,
            "Could not find a remote EndpointCryptoHandle"
        ));
    }
}
