//! Generates the Rust types from `msg/`, `srv/` (this package), `standard/<package>/` (the
//! standard ROS 2 messages the suite uses), `ros2_control/<package>/` (the ros2_control
//! interfaces the sim's controllers offer) and `simulation_interfaces/<package>/` (the ROS 2
//! standard simulation interfaces). See `composuite_msgs_codegen`.

use std::path::{Path, PathBuf};

use composuite_msgs_codegen::{Registry, rust};

/// Folders holding one folder per interface package (other than composuite_msgs itself).
const PACKAGE_FOLDERS: [&str; 3] = ["standard", "ros2_control", "simulation_interfaces"];

fn main() {
    let root = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let mut registry = Registry::default();
    let mut watched = Vec::new();
    match load(&root, &mut registry, &mut watched) {
        Ok(()) => {}
        Err(message) => {
            // A readable error instead of a panic backtrace: this is a user-facing build step.
            eprintln!("error: {message}");
            std::process::exit(1);
        }
    }
    for path in &watched {
        println!("cargo:rerun-if-changed={}", path.display());
    }
    for dir in ["msg", "srv"].into_iter().chain(PACKAGE_FOLDERS) {
        println!("cargo:rerun-if-changed={}", root.join(dir).display());
    }
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("set by cargo")).join("generated.rs");
    std::fs::write(&out, rust::generate(&registry)).expect("write generated.rs");
}

fn load(root: &Path, registry: &mut Registry, watched: &mut Vec<PathBuf>) -> Result<(), String> {
    watched.extend(
        registry
            .load_package("composuite_msgs", root)
            .map_err(|e| e.to_string())?,
    );
    let mut packages = Vec::new();
    for folder in PACKAGE_FOLDERS {
        let folder = root.join(folder);
        packages.extend(
            std::fs::read_dir(&folder)
                .map_err(|e| format!("{}: {e}", folder.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.is_dir()),
        );
    }
    packages.sort();
    for dir in packages {
        let package = dir
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default()
            .to_string();
        watched.extend(
            registry
                .load_package(&package, &dir)
                .map_err(|e| e.to_string())?,
        );
    }
    registry.check_references().map_err(|e| e.to_string())
}
