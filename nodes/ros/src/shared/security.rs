//! Which DDS-Security files a participant joins with, decided as rcl decides it: security is
//! on only when `ROS_SECURITY_ENABLE=true`; the enclave is `ROS_SECURITY_ENCLAVE_OVERRIDE`,
//! else `--ros-args --enclave`, else `/`; its files are
//! `$ROS_SECURITY_KEYSTORE/enclaves/<enclave>/`. Under `ROS_SECURITY_STRATEGY=Enforce` anything
//! missing stops the node; otherwise (permissive) the node warns and joins without security.

use std::path::{Path, PathBuf};

use openssl::asn1::Asn1Time;
use openssl::nid::Nid;
use openssl::pkcs7::{Pkcs7, Pkcs7Flags};
use openssl::stack::Stack;
use openssl::x509::X509;
use openssl::x509::store::X509StoreBuilder;

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

/// What the DDS-Security plugins would refuse in an enclave's files, found before the
/// participant is made and said plainly: which file, what is wrong with it, what to do. (The
/// plugins refuse the same files, but name the wrong thing: an expired grant reads "subject name
/// not found in the permissions document", a changed document as a hash mismatch.) Checks that
/// the identity certificate is in its validity period and signed by the identity CA, that the
/// governance and permissions documents are signed by the permissions CA and unchanged since,
/// and that the permissions grant the certificate's subject something valid now.
pub fn verify_enclave(dir: &Path) -> Result<(), String> {
    let file = |name: &str| dir.join(name).display().to_string();
    let read = |name: &str| {
        std::fs::read(dir.join(name)).map_err(|e| format!("cannot read {}: {e}", file(name)))
    };
    let certificate = |name: &str| {
        X509::from_pem(&read(name)?).map_err(|_| format!("{} is not a PEM certificate", file(name)))
    };
    let remake = "make it again (composuite security create-enclave, or ros2 security \
                  create_enclave) or use another enclave";
    let now = Asn1Time::days_from_now(0).map_err(|e| format!("the clock: {e}"))?;
    let identity_ca = certificate("identity_ca.cert.pem")?;
    let cert = certificate("cert.pem")?;
    for (name, c) in [("identity_ca.cert.pem", &identity_ca), ("cert.pem", &cert)] {
        if c.not_after() < now {
            return Err(format!(
                "{} expired on {}: {remake}",
                file(name),
                c.not_after()
            ));
        }
        if c.not_before() > now {
            return Err(format!(
                "{} is not valid before {} (is this machine's clock right?)",
                file(name),
                c.not_before()
            ));
        }
    }
    let signed_by_ca = identity_ca
        .public_key()
        .and_then(|key| cert.verify(&key))
        .unwrap_or(false);
    if !signed_by_ca {
        return Err(format!(
            "{} is not signed by this keystore's identity CA ({}): an enclave from another \
             keystore? {remake}",
            file("cert.pem"),
            file("identity_ca.cert.pem")
        ));
    }
    let permissions_ca = certificate("permissions_ca.cert.pem")?;
    let mut documents = Vec::new();
    for name in ["governance.p7s", "permissions.p7s"] {
        let text = read(name)?;
        documents.push(signed_content(&text, &permissions_ca).map_err(|problem| {
            format!(
                "{}: {problem}; sign it again with the keystore's permissions CA ({})",
                file(name),
                file("permissions_ca.cert.pem")
            )
        })?);
    }
    let subject = cert
        .subject_name()
        .entries_by_nid(Nid::COMMONNAME)
        .next()
        .map(|cn| String::from_utf8_lossy(cn.data().as_slice()).into_owned())
        .unwrap_or_default();
    let permissions = String::from_utf8_lossy(&documents[1]);
    grant_valid_now(&permissions, &subject, &now)
        .map_err(|problem| format!("{}: {problem}: {remake}", file("permissions.p7s")))
}

/// The document an S/MIME signature (PKCS#7, as `ros2 security` and `composuite security`
/// write them) carries, once its signature is checked against `ca`.
fn signed_content(smime: &[u8], ca: &X509) -> Result<Vec<u8>, String> {
    let (pkcs7, content) =
        Pkcs7::from_smime(smime).map_err(|_| "not an S/MIME signed document".to_string())?;
    let mut store = X509StoreBuilder::new().map_err(|e| e.to_string())?;
    store.add_cert(ca.clone()).map_err(|e| e.to_string())?;
    let store = store.build();
    let certs = Stack::new().map_err(|e| e.to_string())?;
    let mut out = Vec::new();
    pkcs7
        .verify(
            &certs,
            &store,
            content.as_deref(),
            Some(&mut out),
            Pkcs7Flags::TEXT,
        )
        .map_err(|_| {
            "its signature does not verify: changed since it was signed, or signed by \
             another CA"
                .to_string()
        })?;
    Ok(out)
}

/// Whether a grant of the permissions document for `subject` (its certificate's CN) is valid
/// at `now`; the problem in words when none is.
fn grant_valid_now(permissions: &str, subject: &str, now: &Asn1Time) -> Result<(), String> {
    let mut found = None;
    for grant in permissions.split("<grant").skip(1) {
        let field = |tag: &str| {
            let start = grant.find(&format!("<{tag}>"))? + tag.len() + 2;
            let end = grant[start..].find(&format!("</{tag}>"))? + start;
            Some(grant[start..end].trim().to_string())
        };
        let Some(name) = field("subject_name") else {
            continue;
        };
        if name.trim_start_matches("CN=") != subject {
            continue;
        }
        let (Some(not_before), Some(not_after)) = (field("not_before"), field("not_after")) else {
            return Err(format!("the grant for {name} has no validity"));
        };
        let parse = |text: &str| {
            // `2026-11-28T12:21:29` (UTC), as XML Schema dateTime without a zone.
            let digits: String = text.chars().filter(char::is_ascii_digit).take(14).collect();
            Asn1Time::from_str(&format!("{digits}Z")).ok()
        };
        let (Some(start), Some(end)) = (parse(&not_before), parse(&not_after)) else {
            return Err(format!(
                "the grant for {name} has a validity that is not a date ({not_before} .. \
                 {not_after})"
            ));
        };
        if &start <= now && now <= &end {
            return Ok(());
        }
        found = Some(if now > &end {
            format!("the grant for {name} expired on {not_after}")
        } else {
            format!("the grant for {name} is not valid before {not_before}")
        });
    }
    Err(found.unwrap_or_else(|| format!("no grant for CN={subject}")))
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

    /// The grant for the certificate's subject is looked up by name and its validity read as
    /// UTC; an expired, a future or a missing grant is said as such.
    #[test]
    fn a_grant_is_valid_only_for_its_subject_and_its_time() {
        let grant = |subject: &str, from: &str, to: &str| {
            format!(
                "<permissions><grant name=\"g\"><subject_name>CN={subject}</subject_name>\
                 <validity><not_before>{from}</not_before><not_after>{to}</not_after>\
                 </validity><default>DENY</default></grant></permissions>"
            )
        };
        let now = Asn1Time::from_str("20261129120000Z").unwrap();
        let valid = grant("/sim", "2026-11-28T00:00:00", "2036-11-28T00:00:00");
        assert_eq!(grant_valid_now(&valid, "/sim", &now), Ok(()));
        let err = grant_valid_now(&valid, "/agent", &now).unwrap_err();
        assert_eq!(err, "no grant for CN=/agent");
        let expired = grant("/sim", "2026-11-01T00:00:00", "2026-11-29T11:59:59");
        let err = grant_valid_now(&expired, "/sim", &now).unwrap_err();
        assert!(err.contains("expired on 2026-11-29T11:59:59"), "{err}");
        let future = grant("/sim", "2026-11-29T12:00:01", "2036-11-28T00:00:00");
        let err = grant_valid_now(&future, "/sim", &now).unwrap_err();
        assert!(err.contains("not valid before"), "{err}");
        let garbled = grant("/sim", "yesterday", "2036-11-28T00:00:00");
        let err = grant_valid_now(&garbled, "/sim", &now).unwrap_err();
        assert!(err.contains("not a date"), "{err}");
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
        std::fs::remove_dir_all(&root).unwrap();
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
        std::fs::remove_dir_all(&root).unwrap();
    }
}
