//! Which DDS-Security files a participant joins with, decided as rcl decides it: security is
//! on only when `ROS_SECURITY_ENABLE=true`; the enclave is `ROS_SECURITY_ENCLAVE_OVERRIDE`,
//! else `--ros-args --enclave`, else `/`; its files are
//! `$ROS_SECURITY_KEYSTORE/enclaves/<enclave>/`. Under `ROS_SECURITY_STRATEGY=Enforce` anything
//! missing stops the node; otherwise (permissive) the node warns and joins without security.

use std::path::{Path, PathBuf};

use super::environment::SecurityEnvironment;

/// The files of an enclave a participant needs, as rmw_dds_common names them.
pub const ENCLAVE_FILES: [&str; 6] = [
    "identity_ca.cert.pem",
    "cert.pem",
    "key.pem",
    "permissions_ca.cert.pem",
    "governance.p7s",
    "permissions.p7s",
];

/// An enclave's folder in a keystore (`/`, the default enclave, is `enclaves/` itself).
pub fn enclave_dir(keystore: &Path, enclave: &str) -> PathBuf {
    keystore
        .join("enclaves")
        .join(enclave.trim_start_matches('/'))
}

/// How a participant joins.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Join {
    /// Without DDS-Security (it is off, or permissive and its files are missing: the reason
    /// is the warning to log).
    Plain {
        /// Why security is not used where it was asked for (None: it was not asked for).
        warning: Option<String>,
    },
    /// With the files of this enclave folder.
    Secure {
        /// The enclave's name.
        enclave: String,
        /// Its folder.
        dir: PathBuf,
    },
}

/// How to join, from the switches and the node's `--enclave` (if any); an error under
/// Enforce where the files are not all there, in rcl's words.
pub fn decide(security: &SecurityEnvironment, enclave_arg: Option<&str>) -> Result<Join, String> {
    if !security.enable {
        return Ok(Join::Plain { warning: None });
    }
    let enclave = security
        .enclave_override
        .as_deref()
        .or(enclave_arg)
        .unwrap_or("/")
        .to_string();
    let refuse = |problem: String| {
        if security.enforce {
            Err(format!(
                "SECURITY ERROR: {problem} (ROS_SECURITY_STRATEGY=Enforce: not starting \
                 without security)"
            ))
        } else {
            Ok(Join::Plain {
                warning: Some(format!(
                    "{problem}; joining WITHOUT security (ROS_SECURITY_STRATEGY is not \
                     Enforce)"
                )),
            })
        }
    };
    let Some(keystore) = security.keystore.as_deref() else {
        return refuse(
            "ROS_SECURITY_ENABLE=true but ROS_SECURITY_KEYSTORE is unset or empty".into(),
        );
    };
    let dir = enclave_dir(Path::new(keystore), &enclave);
    if !dir.is_dir() {
        return refuse(format!(
            "unable to find a folder matching the enclave '{enclave}' in '{keystore}/enclaves' \
             ({} does not exist)",
            dir.display()
        ));
    }
    let missing: Vec<&str> = ENCLAVE_FILES
        .into_iter()
        .filter(|f| !dir.join(f).is_file())
        .collect();
    if !missing.is_empty() {
        return refuse(format!(
            "couldn't find all security files in {}: missing {}",
            dir.display(),
            missing.join(", ")
        ));
    }
    Ok(Join::Secure { enclave, dir })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn switches(enable: bool, enforce: bool, keystore: Option<&Path>) -> SecurityEnvironment {
        SecurityEnvironment {
            enable,
            enforce,
            keystore: keystore.map(|k| k.display().to_string()),
            enclave_override: None,
        }
    }

    fn keystore_with(enclave: &str, files: &[&str]) -> PathBuf {
        let root = std::env::temp_dir().join(format!(
            "composuite-security-{}-{}",
            std::process::id(),
            enclave.replace('/', "_")
        ));
        let dir = enclave_dir(&root, enclave);
        std::fs::create_dir_all(&dir).unwrap();
        for f in files {
            std::fs::write(dir.join(f), "x").unwrap();
        }
        root
    }

    #[test]
    fn security_is_off_unless_enable_is_exactly_true() {
        let off = switches(false, true, None);
        assert_eq!(decide(&off, Some("/x")), Ok(Join::Plain { warning: None }));
    }

    #[test]
    fn enforce_refuses_what_permissive_warns_about() {
        let root = keystore_with("/sim", &ENCLAVE_FILES[..5]);
        let err = decide(&switches(true, true, Some(&root)), Some("/sim")).unwrap_err();
        assert!(
            err.starts_with("SECURITY ERROR: couldn't find all security files"),
            "{err}"
        );
        assert!(err.contains("missing permissions.p7s"), "{err}");
        let Join::Plain { warning: Some(w) } =
            decide(&switches(true, false, Some(&root)), Some("/sim")).unwrap()
        else {
            panic!("permissive joins without security")
        };
        assert!(w.contains("WITHOUT security"), "{w}");
        let err = decide(&switches(true, true, Some(&root)), Some("/nope")).unwrap_err();
        assert!(
            err.contains("unable to find a folder matching the enclave '/nope'"),
            "{err}"
        );
        let err = decide(&switches(true, true, None), None).unwrap_err();
        assert!(err.contains("ROS_SECURITY_KEYSTORE is unset"), "{err}");
    }

    #[test]
    fn the_override_wins_over_the_argument_and_the_default_is_the_root_enclave() {
        let root = keystore_with("/agent", &ENCLAVE_FILES);
        let mut s = switches(true, true, Some(&root));
        assert_eq!(
            decide(&s, Some("/agent")),
            Ok(Join::Secure {
                enclave: "/agent".into(),
                dir: root.join("enclaves/agent")
            })
        );
        s.enclave_override = Some("/agent".into());
        assert!(matches!(
            decide(&s, Some("/other")),
            Ok(Join::Secure { .. })
        ));
        s.enclave_override = None;
        let err = decide(&s, None).unwrap_err();
        assert!(err.contains("missing identity_ca.cert.pem"), "{err}");
    }
}
