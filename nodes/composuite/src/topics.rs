//! Names of recorded topics: what the bag tools (`bag`, `bag_render`, `replay`) read them by.

/// The namespace of a topic (`/env_00/reward` → `/env_00`, `/reward` → `/`).
pub fn namespace_of(topic: &str) -> String {
    match topic.rsplit_once('/') {
        Some(("", _)) | None => "/".into(),
        Some((ns, _)) => ns.into(),
    }
}
