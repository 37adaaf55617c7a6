//! The DDS library's own log records (RustDDS and ros2-client use the `log` crate) on stderr,
//! in the nodes' line format, so a discovery or transport problem leaves a trace.
//!
//! The level comes from `COMPOSUITE_DDS_LOG` (`off`, `error`, `warn`, `info`, `debug`,
//! `trace`; default `error`): RustDDS is chatty at `info` and below, so raise it only to
//! investigate.

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
        let now = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .unwrap_or_default();
        eprintln!(
            "[{}] [{}.{:09}] [dds {}]: {}",
            record.level(),
            now.as_secs(),
            now.subsec_nanos(),
            record.target(),
            record.args()
        );
    }

    fn flush(&self) {}
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

/// Send the `log` crate's records to stderr at `level`. Once per process; a second call (a
/// logger already set, e.g. in tests) only changes the level.
pub fn install(level: log::LevelFilter) {
    static LOGGER: StderrLog = StderrLog;
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
}
