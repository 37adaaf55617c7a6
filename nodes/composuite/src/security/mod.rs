//! `composuite security`: SROS2 keystores and enclaves made without a ROS install, in the
//! layout `ros2 security create_keystore` / `create_enclave` write, so ROS tools and the
//! suite read the same folder.

mod documents;
mod pki;
mod policy;

use std::fs;
use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};

use composuite_ros::grants::{self, Role};
use composuite_ros::shared::environment::MAX_DOMAIN_ID;
use composuite_ros::shared::ros_args::is_fully_qualified_name;
use composuite_ros::shared::security::enclave_dir;
use documents::Grant;
use pki::{Authority, Validity};

/// Make and inspect SROS2 keystores (DDS-Security: authenticated participants, encrypted
/// topics, per-enclave permissions) without a ROS install, in the layout `ros2 security`
/// writes:
///
///   KEYSTORE/public/ca.cert.pem           the CA's certificate (identity_ca.cert.pem and
///                                         permissions_ca.cert.pem link to it)
///   KEYSTORE/private/ca.key.pem           the CA's key (and the two links)
///   KEYSTORE/enclaves/governance.xml|p7s  the domain's rules, signed by the CA
///   KEYSTORE/enclaves/ENCLAVE/            cert.pem, key.pem, permissions.xml|p7s, and links
///                                         to governance.p7s and the two CA certificates
///
/// Keys are EC P-256, unencrypted PKCS#8 (the security plugins take no password);
/// certificates are valid from a day before creation for --days days; documents are signed as
/// S/MIME (PKCS#7, detached, text).
///
/// Examples:
///   composuite security create-keystore ~/sros2_keystore
///   composuite security create-enclave ~/sros2_keystore /composuite/sim
///   composuite security list-enclaves ~/sros2_keystore
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct SecurityArgs {
    #[command(subcommand)]
    command: SecurityCommand,
}

#[derive(Subcommand, Debug)]
enum SecurityCommand {
    /// Create a keystore: the CA, and the governance of the domain signed by it. A complete
    /// keystore already there is left as it is.
    CreateKeystore {
        /// The keystore's folder (created; must be new, empty or a keystore).
        keystore: PathBuf,
        /// The domain the governance covers (default: ROS_DOMAIN_ID, else 0).
        #[arg(long)]
        domain_id: Option<u32>,
        /// How long the CA's certificate is valid.
        #[arg(long, default_value_t = 3650)]
        days: u32,
    },
    /// Create an enclave: its key, its certificate (CN = the enclave) signed by the keystore's
    /// CA, and its permissions signed by the CA — by default what `ros2 security
    /// create_enclave` grants without a policy (every rt/, rq/ and rr/ topic both ways).
    CreateEnclave {
        /// The keystore (made by create-keystore or `ros2 security create_keystore`).
        keystore: PathBuf,
        /// The enclave: a fully qualified ROS name such as /composuite/sim (`/` is the
        /// default enclave of every ROS node).
        enclave: String,
        /// The domain the permissions allow (default: ROS_DOMAIN_ID, else 0).
        #[arg(long)]
        domain_id: Option<u32>,
        /// How long the certificate and the permissions are valid.
        #[arg(long, default_value_t = 3650)]
        days: u32,
        /// Instead of the default grant: the DDS topics it may publish (wildcards * and ?; ROS
        /// topic /ns/name is rt/ns/name, a service's request rq/ns/nameRequest and its reply
        /// rr/ns/nameReply). ros_discovery_info is always allowed.
        #[arg(long, num_args = 1.., value_name = "TOPIC", requires = "allow_subscribe")]
        allow_publish: Vec<String>,
        /// With --allow-publish: the DDS topics it may subscribe to.
        #[arg(long, num_args = 1.., value_name = "TOPIC", requires = "allow_publish")]
        allow_subscribe: Vec<String>,
        /// Instead of the default grant: exactly what these roles need in the environments of
        /// --namespace — a node of the suite (sim, task_manager, reward, recorder), `player`
        /// (`composuite play`), or `agent` (commands and resets the environment and reads all
        /// it publishes, but publishes none of the suite's outputs). Several roles add up (the
        /// enclave of a composed process, one participant for all its nodes: sim task_manager
        /// reward).
        #[arg(long, num_args = 1.., value_name = "ROLE", conflicts_with = "allow_publish")]
        grant: Vec<String>,
        /// With --grant: the environments' namespaces (wildcards allowed, e.g. '/train/env_*';
        /// default: the root namespace `/`).
        #[arg(long, num_args = 1.., value_name = "NS", requires = "grant")]
        namespace: Vec<String>,
        /// Instead of the default grant: what an sros2 policy file (format 0.2.0, as `ros2
        /// security create_enclave --policy` reads) gives this enclave.
        #[arg(long, value_name = "FILE", conflicts_with_all = ["allow_publish", "grant"])]
        policy: Option<PathBuf>,
    },
    /// List the keystore's enclaves, one per line.
    ListEnclaves {
        /// The keystore.
        keystore: PathBuf,
    },
}

/// Run `composuite security ...`.
pub fn run(args: &SecurityArgs) -> Result<(), String> {
    match &args.command {
        SecurityCommand::CreateKeystore {
            keystore,
            domain_id,
            days,
        } => {
            let made = create_keystore(keystore, domain(*domain_id)?, *days)?;
            if made {
                println!("created keystore {}", keystore.display());
            } else {
                println!(
                    "{} is a keystore already: left as it is",
                    keystore.display()
                );
            }
            Ok(())
        }
        SecurityCommand::CreateEnclave {
            keystore,
            enclave,
            domain_id,
            days,
            allow_publish,
            allow_subscribe,
            grant: roles,
            namespace,
            policy,
        } => {
            let grant = if let Some(file) = policy {
                let xml = fs::read_to_string(file)
                    .map_err(|e| format!("--policy {}: {e}", file.display()))?;
                policy::grant_from_policy(&xml, &file.display().to_string(), enclave)?
            } else if !roles.is_empty() {
                role_grant(roles, namespace)?
            } else if allow_publish.is_empty() {
                Grant::ros_default()
            } else {
                Grant::of(allow_publish, allow_subscribe)
            };
            let dir = create_enclave(keystore, enclave, domain(*domain_id)?, *days, &grant)?;
            println!("created enclave {enclave} in {}", dir.display());
            Ok(())
        }
        SecurityCommand::ListEnclaves { keystore } => {
            for enclave in list_enclaves(keystore)? {
                println!("{enclave}");
            }
            Ok(())
        }
    }
}

/// What `roles` need in the environments of `namespaces` (the root one if none), each topic
/// once, in the order first needed.
fn role_grant(roles: &[String], namespaces: &[String]) -> Result<Grant, String> {
    let root = ["/".to_string()];
    let namespaces = if namespaces.is_empty() {
        &root[..]
    } else {
        namespaces
    };
    if let Some(bad) = namespaces.iter().find(|n| !n.starts_with('/')) {
        return Err(format!(
            "--namespace {bad} is invalid; it must be absolute, e.g. /env_00 or '/train/env_*'"
        ));
    }
    let mut topics = grants::Topics::default();
    for name in roles {
        let role = Role::parse(name).ok_or_else(|| {
            format!(
                "--grant {name}: unknown role; valid: {}",
                Role::NAMES.join(", ")
            )
        })?;
        for namespace in namespaces {
            topics.merge(grants::grant(role, namespace));
        }
    }
    Ok(Grant::of(&topics.publish, &topics.subscribe))
}

/// The domain id given, else `ROS_DOMAIN_ID`, else 0 (what `ros2 security` does).
fn domain(given: Option<u32>) -> Result<u32, String> {
    let (id, source) = match (given, std::env::var("ROS_DOMAIN_ID")) {
        (Some(id), _) => (id, "--domain-id".to_string()),
        (None, Ok(text)) if !text.trim().is_empty() => match text.trim().parse() {
            Ok(id) => (id, format!("ROS_DOMAIN_ID={text:?}")),
            Err(_) => (u32::MAX, format!("ROS_DOMAIN_ID={text:?}")),
        },
        _ => (0, String::new()),
    };
    let max = u32::from(MAX_DOMAIN_ID);
    if id > max {
        return Err(format!(
            "{source} is not a domain id (a whole number, 0 to {max})"
        ));
    }
    Ok(id)
}

/// The keystore's files that `create_keystore` writes (links included), relative to it.
const KEYSTORE_FILES: [&str; 8] = [
    "public/ca.cert.pem",
    "public/identity_ca.cert.pem",
    "public/permissions_ca.cert.pem",
    "private/ca.key.pem",
    "private/identity_ca.key.pem",
    "private/permissions_ca.key.pem",
    "enclaves/governance.xml",
    "enclaves/governance.p7s",
];

/// The keystore's files that are missing.
fn missing_keystore_files(keystore: &Path) -> Vec<&'static str> {
    KEYSTORE_FILES
        .into_iter()
        .filter(|f| !keystore.join(f).exists())
        .collect()
}

fn io_error(what: &str, path: &Path, e: std::io::Error) -> String {
    format!("cannot {what} {}: {e}", path.display())
}

fn write(path: &Path, contents: &[u8], private: bool) -> Result<(), String> {
    fs::write(path, contents).map_err(|e| io_error("write", path, e))?;
    if private {
        use std::os::unix::fs::PermissionsExt;
        fs::set_permissions(path, fs::Permissions::from_mode(0o600))
            .map_err(|e| io_error("restrict", path, e))?;
    }
    Ok(())
}

/// A relative symbolic link at `link` to `target` (relative to the link's folder); one that
/// is there already and points there is kept (an enclave made again after its own files were
/// removed, as the refusal to overwrite them says to do).
fn link(target: &str, link: &Path) -> Result<(), String> {
    if fs::read_link(link).is_ok_and(|there| there == Path::new(target)) {
        return Ok(());
    }
    std::os::unix::fs::symlink(target, link).map_err(|e| io_error("link", link, e))
}

fn crypto(what: &str) -> impl FnOnce(openssl::error::ErrorStack) -> String + '_ {
    move |e| format!("cannot {what}: {e}")
}

fn now() -> i64 {
    chrono::Utc::now().timestamp()
}

/// Make the keystore at `keystore`; false where a complete one is there already.
pub fn create_keystore(keystore: &Path, domain: u32, days: u32) -> Result<bool, String> {
    let missing = missing_keystore_files(keystore);
    if missing.is_empty() {
        return Ok(false);
    }
    let occupied = fs::read_dir(keystore).is_ok_and(|mut entries| entries.next().is_some());
    if occupied {
        return Err(format!(
            "{} holds files but is not a complete keystore (missing {}); give a new or empty \
             folder, or remove it",
            keystore.display(),
            missing.join(", ")
        ));
    }
    for folder in ["public", "private", "enclaves"] {
        let path = keystore.join(folder);
        fs::create_dir_all(&path).map_err(|e| io_error("create", &path, e))?;
    }
    let validity = Validity::from_day_before(now(), i64::from(days));
    let ca = Authority::new("sros2testCA", validity).map_err(crypto("make the CA"))?;
    let cert = ca.cert.to_pem().map_err(crypto("encode the CA"))?;
    let key = pki::key_pem(&ca.key).map_err(crypto("encode the CA's key"))?;
    write(&keystore.join("public/ca.cert.pem"), &cert, false)?;
    write(&keystore.join("private/ca.key.pem"), &key, true)?;
    for role in ["identity_ca", "permissions_ca"] {
        link(
            "ca.cert.pem",
            &keystore.join(format!("public/{role}.cert.pem")),
        )?;
        link(
            "ca.key.pem",
            &keystore.join(format!("private/{role}.key.pem")),
        )?;
    }
    let governance = documents::governance(domain);
    let signed = ca
        .sign(governance.as_bytes())
        .map_err(crypto("sign the governance"))?;
    write(
        &keystore.join("enclaves/governance.xml"),
        governance.as_bytes(),
        false,
    )?;
    write(&keystore.join("enclaves/governance.p7s"), &signed, false)?;
    Ok(true)
}

/// Make `enclave` in `keystore` with the permissions `grant`; returns its folder.
pub fn create_enclave(
    keystore: &Path,
    enclave: &str,
    domain: u32,
    days: u32,
    grant: &Grant,
) -> Result<PathBuf, String> {
    if !is_fully_qualified_name(enclave) {
        return Err(format!(
            "enclave {enclave:?} is not a fully qualified ROS name: `/`, or `/`-separated \
             tokens of letters, digits and underscores not starting with a digit, such as \
             /composuite/sim"
        ));
    }
    let missing = missing_keystore_files(keystore);
    if !missing.is_empty() {
        return Err(format!(
            "{} is not a keystore (missing {}); make one with `composuite security \
             create-keystore {}`",
            keystore.display(),
            missing.join(", "),
            keystore.display()
        ));
    }
    let dir = enclave_dir(keystore, enclave);
    if dir.join("cert.pem").exists() {
        return Err(format!(
            "enclave {enclave} exists already in {}; remove its files to make it again",
            keystore.display()
        ));
    }
    fs::create_dir_all(&dir).map_err(|e| io_error("create", &dir, e))?;
    let read = |f: &str| {
        let path = keystore.join(f);
        fs::read(&path).map_err(|e| io_error("read", &path, e))
    };
    let ca = Authority::from_pem(&read("private/ca.key.pem")?, &read("public/ca.cert.pem")?)
        .map_err(crypto("read the keystore's CA"))?;
    let now = now();
    let validity = Validity::from_day_before(now, i64::from(days));
    let key = pki::new_key().map_err(crypto("make the enclave's key"))?;
    let cert = ca
        .issue(&key, enclave, validity)
        .map_err(crypto("issue the enclave's certificate"))?;
    let stamp = |t: i64| {
        chrono::DateTime::from_timestamp(t, 0)
            .expect("a time within chrono's range")
            .format("%Y-%m-%dT%H:%M:%S")
            .to_string()
    };
    let permissions = documents::permissions(
        enclave,
        domain,
        &stamp(validity.not_before),
        &stamp(validity.not_after),
        grant,
    );
    let signed = ca
        .sign(permissions.as_bytes())
        .map_err(crypto("sign the permissions"))?;
    let pem = cert.to_pem().map_err(crypto("encode the certificate"))?;
    let key_pem = pki::key_pem(&key).map_err(crypto("encode the key"))?;
    write(&dir.join("cert.pem"), &pem, false)?;
    write(&dir.join("key.pem"), &key_pem, true)?;
    write(&dir.join("permissions.xml"), permissions.as_bytes(), false)?;
    write(&dir.join("permissions.p7s"), &signed, false)?;
    // Links up to the keystore's shared files, relative so the keystore can move.
    let depth = enclave.split('/').filter(|t| !t.is_empty()).count();
    let up = "../".repeat(depth);
    if depth > 0 {
        link(&format!("{up}governance.p7s"), &dir.join("governance.p7s"))?;
    }
    for role in ["identity_ca", "permissions_ca"] {
        let name = format!("{role}.cert.pem");
        link(&format!("{up}../public/{name}"), &dir.join(&name))?;
    }
    Ok(dir)
}

/// The enclaves of `keystore` (folders under `enclaves/` with a certificate), sorted.
pub fn list_enclaves(keystore: &Path) -> Result<Vec<String>, String> {
    let root = keystore.join("enclaves");
    if !root.is_dir() {
        return Err(format!(
            "{} is not a keystore (no enclaves/ folder)",
            keystore.display()
        ));
    }
    let mut found = Vec::new();
    let mut folders = vec![root.clone()];
    while let Some(folder) = folders.pop() {
        if folder.join("cert.pem").is_file() {
            let relative = folder.strip_prefix(&root).expect("under the root");
            found.push(format!("/{}", relative.display()));
        }
        let entries = fs::read_dir(&folder).map_err(|e| io_error("read", &folder, e))?;
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() && !path.is_symlink() {
                folders.push(path);
            }
        }
    }
    found.sort();
    Ok(found)
}
