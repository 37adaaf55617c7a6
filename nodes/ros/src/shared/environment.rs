//! The ROS 2 environment variables a node must honour (ros2-client reads none of them).

use std::fmt;

/// How far discovery reaches (`ROS_AUTOMATIC_DISCOVERY_RANGE`, Jazzy; `ROS_LOCALHOST_ONLY=1`
/// is the deprecated way to ask for `Localhost`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DiscoveryRange {
    /// No automatic discovery (only static peers).
    Off,
    /// Only this machine.
    Localhost,
    /// The local network (the default).
    Subnet,
}

/// Environment settings that decide where a node talks.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RosEnvironment {
    /// `ROS_DOMAIN_ID` (0 when unset).
    pub domain_id: u16,
    /// Discovery range.
    pub discovery_range: DiscoveryRange,
    /// DDS-Security, as rcl reads it.
    pub security: SecurityEnvironment,
}

/// rcl's security switches, read as rcl reads them: each is on only at its exact value.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct SecurityEnvironment {
    /// `ROS_SECURITY_ENABLE` is exactly `true`.
    pub enable: bool,
    /// `ROS_SECURITY_STRATEGY` is exactly `Enforce` (anything else: permissive — run without
    /// security where its files are missing).
    pub enforce: bool,
    /// `ROS_SECURITY_KEYSTORE` (unset or empty: none).
    pub keystore: Option<String>,
    /// `ROS_SECURITY_ENCLAVE_OVERRIDE`: the enclave, whatever `--enclave` says.
    pub enclave_override: Option<String>,
}

/// An environment variable with a value ROS would refuse.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EnvironmentError(pub String);

impl fmt::Display for EnvironmentError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for EnvironmentError {}

/// The largest domain id rmw accepts on Linux (ports stay below 65535).
pub const MAX_DOMAIN_ID: u16 = 232;

impl RosEnvironment {
    /// Read the settings through `get` (e.g. `|k| std::env::var(k).ok()`).
    pub fn read(get: impl Fn(&str) -> Option<String>) -> Result<RosEnvironment, EnvironmentError> {
        let domain_id = match get("ROS_DOMAIN_ID")
            .map(|v| v.trim().to_string())
            .filter(|v| !v.is_empty())
        {
            None => 0,
            Some(v) => v
                .parse::<u16>()
                .ok()
                .filter(|d| *d <= MAX_DOMAIN_ID)
                .ok_or_else(|| {
                    EnvironmentError(format!(
                        "ROS_DOMAIN_ID={v} is invalid; valid: 0..={MAX_DOMAIN_ID}"
                    ))
                })?,
        };
        let range = get("ROS_AUTOMATIC_DISCOVERY_RANGE")
            .map(|v| v.trim().to_ascii_uppercase())
            .filter(|v| !v.is_empty());
        let discovery_range = match range.as_deref() {
            Some("OFF") => DiscoveryRange::Off,
            Some("LOCALHOST") => DiscoveryRange::Localhost,
            Some("SUBNET") | Some("SYSTEM_DEFAULT") => DiscoveryRange::Subnet,
            Some(other) => {
                return Err(EnvironmentError(format!(
                    "ROS_AUTOMATIC_DISCOVERY_RANGE={other} is invalid; valid: OFF, LOCALHOST, SUBNET, SYSTEM_DEFAULT"
                )));
            }
            None if get("ROS_LOCALHOST_ONLY").as_deref().map(str::trim) == Some("1") => {
                DiscoveryRange::Localhost
            }
            None => DiscoveryRange::Subnet,
        };
        let non_empty = |key: &str| get(key).filter(|v| !v.is_empty());
        let security = SecurityEnvironment {
            enable: get("ROS_SECURITY_ENABLE").as_deref() == Some("true"),
            enforce: get("ROS_SECURITY_STRATEGY").as_deref() == Some("Enforce"),
            keystore: non_empty("ROS_SECURITY_KEYSTORE"),
            enclave_override: non_empty("ROS_SECURITY_ENCLAVE_OVERRIDE"),
        };
        Ok(RosEnvironment {
            domain_id,
            discovery_range,
            security,
        })
    }
}
