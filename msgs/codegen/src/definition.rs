//! The full message definition text (`ros2msg` encoding) rosbag2 stores in MCAP schemas.
//!
//! Layout, as Jazzy's `LocalMessageDefinitionSource` produces it: the root type's file text
//! verbatim; then, for each dependency not yet written, a newline, a line of 80 `=`, a line
//! `MSG: pkg/Type` (the name as written in the referring field, package-qualified), and that
//! type's text. Direct dependencies are visited in sorted order, each expanded depth-first
//! before its next sibling.

use std::collections::{BTreeMap, HashSet};

use crate::Registry;
use crate::spec::{BaseType, MessageSpec, TypeName};

const SEPARATOR: &str =
    "================================================================================";

/// The complete `ros2msg` definition of `root`.
pub fn full_text(registry: &Registry, root: &TypeName) -> String {
    let mut seen: HashSet<String> = HashSet::new();
    append(registry, registry.message(root), &mut seen)
}

fn append(registry: &Registry, msg: &MessageSpec, seen: &mut HashSet<String>) -> String {
    let mut text = msg.text.clone();
    for (written, name) in dependencies(msg) {
        if seen.insert(written.clone()) {
            let dep = registry.message(&name);
            text.push('\n');
            text.push_str(SEPARATOR);
            text.push_str("\nMSG: ");
            text.push_str(&written);
            text.push('\n');
            text.push_str(&append(registry, dep, seen));
        }
    }
    text
}

/// Direct dependencies keyed by the name as written (`pkg/Type`), sorted and unique.
fn dependencies(msg: &MessageSpec) -> BTreeMap<String, TypeName> {
    msg.fields
        .iter()
        .filter_map(|f| match &f.ty.base {
            BaseType::Nested { written, name } => Some((written.clone(), name.clone())),
            _ => None,
        })
        .collect()
}
