//! `composuite security`: the keystore and enclaves it writes have `ros2 security`'s layout,
//! and OpenSSL's own command line (a verifier nobody here wrote) accepts the certificates and
//! signed documents — and refuses them once changed or checked against another CA.

use std::fs;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn composuite(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_composuite"))
        .args(args)
        .env_remove("ROS_DOMAIN_ID")
        .output()
        .expect("runs")
}

fn openssl(args: &[&str]) -> Output {
    Command::new("openssl")
        .args(args)
        .output()
        .expect("openssl runs")
}

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A fresh folder under the target's temporary directory.
fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("security-{name}"));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Every file under `root` as `relative path` or `relative path -> link target`, sorted.
fn listing(root: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut folders = vec![root.to_path_buf()];
    while let Some(folder) = folders.pop() {
        for entry in fs::read_dir(&folder).unwrap() {
            let p = entry.unwrap().path();
            let rel = p.strip_prefix(root).unwrap().display().to_string();
            if p.is_symlink() {
                out.push(format!("{rel} -> {}", fs::read_link(&p).unwrap().display()));
            } else if p.is_dir() {
                folders.push(p);
            } else {
                out.push(rel);
            }
        }
    }
    out.sort();
    out
}

#[test]
fn a_keystore_and_its_enclaves_have_the_ros2_security_layout() {
    let ks = scratch("layout").join("keystore");
    let made = composuite(&["security", "create-keystore", path(&ks)]);
    assert!(made.status.success(), "{}", stderr(&made));
    for enclave in ["/composuite/sim", "/"] {
        let out = composuite(&["security", "create-enclave", path(&ks), enclave]);
        assert!(out.status.success(), "{}", stderr(&out));
    }
    assert_eq!(
        listing(&ks),
        [
            "enclaves/cert.pem",
            "enclaves/composuite/sim/cert.pem",
            "enclaves/composuite/sim/governance.p7s -> ../../governance.p7s",
            "enclaves/composuite/sim/identity_ca.cert.pem -> ../../../public/identity_ca.cert.pem",
            "enclaves/composuite/sim/key.pem",
            "enclaves/composuite/sim/permissions.p7s",
            "enclaves/composuite/sim/permissions.xml",
            "enclaves/composuite/sim/permissions_ca.cert.pem -> ../../../public/permissions_ca.cert.pem",
            "enclaves/governance.p7s",
            "enclaves/governance.xml",
            "enclaves/identity_ca.cert.pem -> ../public/identity_ca.cert.pem",
            "enclaves/key.pem",
            "enclaves/permissions.p7s",
            "enclaves/permissions.xml",
            "enclaves/permissions_ca.cert.pem -> ../public/permissions_ca.cert.pem",
            "private/ca.key.pem",
            "private/identity_ca.key.pem -> ca.key.pem",
            "private/permissions_ca.key.pem -> ca.key.pem",
            "public/ca.cert.pem",
            "public/identity_ca.cert.pem -> ca.cert.pem",
            "public/permissions_ca.cert.pem -> ca.cert.pem",
        ]
    );
    for key in ["private/ca.key.pem", "enclaves/composuite/sim/key.pem"] {
        let mode = fs::metadata(ks.join(key)).unwrap().permissions().mode();
        assert_eq!(mode & 0o777, 0o600, "{key}");
        let pem = fs::read_to_string(ks.join(key)).unwrap();
        assert!(
            pem.starts_with("-----BEGIN PRIVATE KEY-----"),
            "PKCS#8, unencrypted: {key}"
        );
    }
    let listed = composuite(&["security", "list-enclaves", path(&ks)]);
    assert_eq!(stdout(&listed), "/\n/composuite/sim\n");
    // Made again, the keystore is left alone.
    let before = fs::read(ks.join("private/ca.key.pem")).unwrap();
    let again = composuite(&["security", "create-keystore", path(&ks)]);
    assert!(again.status.success() && stdout(&again).contains("left as it is"));
    assert_eq!(fs::read(ks.join("private/ca.key.pem")).unwrap(), before);
}

#[test]
fn openssl_accepts_what_the_ca_signed_and_nothing_else() {
    let ks = scratch("openssl").join("keystore");
    assert!(
        composuite(&["security", "create-keystore", path(&ks), "--domain-id", "7"])
            .status
            .success()
    );
    assert!(
        composuite(&["security", "create-enclave", path(&ks), "/agent"])
            .status
            .success()
    );
    let dir = ks.join("enclaves/agent");
    let ca = dir.join("identity_ca.cert.pem");
    let verify = openssl(&["verify", "-CAfile", path(&ca), path(&dir.join("cert.pem"))]);
    assert!(
        stdout(&verify).trim_end().ends_with(": OK"),
        "{}",
        stderr(&verify)
    );
    let subject = openssl(&[
        "x509",
        "-noout",
        "-subject",
        "-in",
        path(&dir.join("cert.pem")),
    ]);
    assert_eq!(stdout(&subject).trim(), "subject=CN = /agent");
    // Each signed document, read through the enclave's own links, verifies and carries the
    // document beside it.
    for (signed, document) in [
        (
            dir.join("governance.p7s"),
            ks.join("enclaves/governance.xml"),
        ),
        (dir.join("permissions.p7s"), dir.join("permissions.xml")),
    ] {
        let ca = dir.join("permissions_ca.cert.pem");
        let out = openssl(&[
            "smime",
            "-verify",
            "-text",
            "-in",
            path(&signed),
            "-CAfile",
            path(&ca),
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        assert!(stderr(&out).contains("Verification successful"));
        let carried = stdout(&out).replace("\r\n", "\n");
        assert_eq!(carried, fs::read_to_string(&document).unwrap());
    }
    let governance = fs::read_to_string(ks.join("enclaves/governance.xml")).unwrap();
    assert!(governance.contains("<id>7</id>"));
    let permissions = fs::read_to_string(dir.join("permissions.xml")).unwrap();
    assert!(permissions.contains("<id>0</id>") && permissions.contains("CN=/agent"));
    // A changed document no longer verifies.
    let p7s = dir.join("permissions.p7s");
    let text = fs::read_to_string(&p7s).unwrap();
    let tampered = scratch("openssl-tampered").join("permissions.p7s");
    fs::write(
        &tampered,
        text.replace("<default>DENY</default>", "<default>ALLOW</default>"),
    )
    .unwrap();
    let out = openssl(&[
        "smime",
        "-verify",
        "-text",
        "-in",
        path(&tampered),
        "-CAfile",
        path(&ca),
    ]);
    assert!(
        !out.status.success(),
        "a changed permissions document verified"
    );
    // Nor does a certificate checked against another keystore's CA.
    let other = scratch("openssl-other").join("keystore");
    assert!(
        composuite(&["security", "create-keystore", path(&other)])
            .status
            .success()
    );
    let foreign = other.join("public/ca.cert.pem");
    let out = openssl(&[
        "verify",
        "-CAfile",
        path(&foreign),
        path(&dir.join("cert.pem")),
    ]);
    assert!(!out.status.success(), "verified against a foreign CA");
}

#[test]
fn an_enclave_can_be_granted_exactly_its_topics() {
    let ks = scratch("grant").join("keystore");
    assert!(
        composuite(&["security", "create-keystore", path(&ks)])
            .status
            .success()
    );
    let out = composuite(&[
        "security",
        "create-enclave",
        path(&ks),
        "/agent",
        "--allow-publish",
        "rt/env_00/reference_action",
        "rq/env_00/*",
        "--allow-subscribe",
        "rt/env_00/*",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let xml = fs::read_to_string(ks.join("enclaves/agent/permissions.xml")).unwrap();
    let publish = &xml[xml.find("<publish>").unwrap()..xml.find("</publish>").unwrap()];
    let subscribe = &xml[xml.find("<subscribe>").unwrap()..xml.find("</subscribe>").unwrap()];
    for topic in [
        "rt/env_00/reference_action",
        "rq/env_00/*",
        "ros_discovery_info",
    ] {
        assert!(
            publish.contains(&format!("<topic>{topic}</topic>")),
            "{publish}"
        );
    }
    assert!(!publish.contains("rt/*") && !publish.contains("rt/env_00/*"));
    assert!(
        subscribe.contains("<topic>rt/env_00/*</topic>"),
        "{subscribe}"
    );
    // One list without the other is refused by the command line.
    let out = composuite(&[
        "security",
        "create-enclave",
        path(&ks),
        "/b",
        "--allow-publish",
        "x",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("--allow-subscribe"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn bad_input_is_refused_saying_what_is_valid() {
    let root = scratch("bad");
    let ks = root.join("keystore");
    let out = composuite(&["security", "create-enclave", path(&ks), "/x"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("is not a keystore") && stderr(&out).contains("create-keystore"));
    assert!(
        composuite(&["security", "create-keystore", path(&ks)])
            .status
            .success()
    );
    let out = composuite(&["security", "create-enclave", path(&ks), "talker"]);
    assert!(stderr(&out).contains("\"talker\" is not a fully qualified ROS name"));
    assert!(
        composuite(&["security", "create-enclave", path(&ks), "/x"])
            .status
            .success()
    );
    let out = composuite(&["security", "create-enclave", path(&ks), "/x"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("enclave /x exists already"));
    let cluttered = root.join("cluttered");
    fs::create_dir_all(&cluttered).unwrap();
    fs::write(cluttered.join("notes.txt"), "mine").unwrap();
    let out = composuite(&["security", "create-keystore", path(&cluttered)]);
    assert!(stderr(&out).contains("holds files but is not a complete keystore"));
    assert_eq!(
        fs::read_to_string(cluttered.join("notes.txt")).unwrap(),
        "mine"
    );
    let out = Command::new(env!("CARGO_BIN_EXE_composuite"))
        .args(["security", "create-keystore", path(&root.join("k2"))])
        .env("ROS_DOMAIN_ID", "seven")
        .output()
        .unwrap();
    assert!(
        stderr(&out)
            .contains("ROS_DOMAIN_ID=\"seven\" is not a domain id (a whole number, 0 to 232)")
    );
    let out = composuite(&[
        "security",
        "create-keystore",
        path(&root.join("k3")),
        "--domain-id",
        "233",
    ]);
    assert!(
        stderr(&out).contains("--domain-id is not a domain id"),
        "{}",
        stderr(&out)
    );
    assert!(!root.join("k3").exists());
}

/// What a node checks before it joins (`verify_enclave`): an enclave as made passes; a changed
/// governance or permissions document, an identity from another keystore and an expired
/// certificate each fail, naming the file and what is wrong with it.
#[test]
fn a_node_refuses_changed_foreign_and_expired_enclaves_saying_which_file() {
    use composuite_ros::shared::security::verify_enclave;
    let root = scratch("verify");
    let make = |name: &str, days: &str| {
        let ks = root.join(name);
        assert!(
            composuite(&["security", "create-keystore", path(&ks)])
                .status
                .success()
        );
        let out = composuite(&["security", "create-enclave", path(&ks), "/", "--days", days]);
        assert!(out.status.success(), "{}", stderr(&out));
        ks.join("enclaves")
    };
    let good = make("good", "30");
    assert_eq!(verify_enclave(&good), Ok(()));

    for (document, tag) in [
        ("governance.p7s", "enable_join_access_control"),
        ("permissions.p7s", "subject_name"),
    ] {
        let ks = make(&format!("changed-{document}"), "30");
        let file = ks.join(document);
        let text = fs::read_to_string(&file).unwrap();
        let opening = format!("<{tag}>");
        assert!(text.contains(&opening), "{document} has {opening}");
        // One character of the signed text changed.
        let changed = text.replacen(&opening, &format!("{opening} "), 1);
        fs::write(&file, changed).unwrap();
        let err = verify_enclave(&ks).unwrap_err();
        assert!(
            err.contains(document) && err.contains("signature does not verify"),
            "{err}"
        );
    }

    let foreign = make("foreign", "30");
    let other = make("other", "30");
    for file in ["cert.pem", "key.pem"] {
        fs::copy(other.join(file), foreign.join(file)).unwrap();
    }
    let err = verify_enclave(&foreign).unwrap_err();
    assert!(
        err.contains("cert.pem is not signed by this keystore's identity CA"),
        "{err}"
    );

    // Valid for 0 days from a day back (the tool's allowance for lagging clocks): expired.
    let expired = make("expired", "0");
    let err = verify_enclave(&expired).unwrap_err();
    assert!(err.contains("cert.pem expired on"), "{err}");
}
