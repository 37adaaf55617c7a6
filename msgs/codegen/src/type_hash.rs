//! RIHS01 type hashes, computed the way ROS 2 Jazzy's `rosidl_generator_type_description` does.
//!
//! The hash is the SHA-256 of a JSON document (Python `json.dumps` with its default `", "` and
//! `": "` separators, keys in this order) holding the type's description and the descriptions of
//! every type it references, sorted by name. Constants and default values are not part of it.
//! A service is described by three nested fields (`request_message`, `response_message`,
//! `event_message`); the event message is an ordinary (synthesized) message of the registry.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use sha2::{Digest, Sha256};

use crate::Registry;
use crate::spec::{ArrayKind, BaseType, Primitive, TypeName};

/// ROS 2 `type_description_interfaces/msg/FieldType` ids.
mod field_type {
    pub const NESTED_TYPE: u8 = 1;
    pub const STRING: u8 = 17;
    pub const BOUNDED_STRING: u8 = 21;
    pub const ARRAY_OFFSET: u8 = 48;
    pub const BOUNDED_SEQUENCE_OFFSET: u8 = 96;
    pub const UNBOUNDED_SEQUENCE_OFFSET: u8 = 144;
}

fn primitive_id(p: Primitive) -> u8 {
    match p {
        Primitive::Int8 => 2,
        Primitive::UInt8 => 3,
        Primitive::Int16 => 4,
        Primitive::UInt16 => 5,
        Primitive::Int32 => 6,
        Primitive::UInt32 => 7,
        Primitive::Int64 => 8,
        Primitive::UInt64 => 9,
        Primitive::Float32 => 10,
        Primitive::Float64 => 11,
        // Jazzy turns a .msg `char` into IDL `uint8` before hashing (rosbags uses 13 here).
        Primitive::Char => 3,
        Primitive::Bool => 15,
        Primitive::Byte => 16,
    }
}

/// One field as the hash sees it.
#[derive(Debug, Clone)]
struct HashField {
    name: String,
    type_id: u8,
    capacity: usize,
    string_capacity: usize,
    nested_type_name: String,
}

/// The description of a message, a service, or a service's event message.
fn describe(registry: &Registry, name: &TypeName) -> Vec<HashField> {
    if let Some(service) = registry.services.get(name) {
        let nested = |field: &str, suffix: &str| HashField {
            name: field.into(),
            type_id: field_type::NESTED_TYPE,
            capacity: 0,
            string_capacity: 0,
            nested_type_name: format!("{}_{suffix}", service.name),
        };
        return vec![
            nested("request_message", "Request"),
            nested("response_message", "Response"),
            nested("event_message", "Event"),
        ];
    }
    let msg = registry.message(name);
    if msg.fields.is_empty() {
        // ROS gives every empty structure one placeholder octet.
        return vec![HashField {
            name: "structure_needs_at_least_one_member".into(),
            type_id: primitive_id(Primitive::UInt8),
            capacity: 0,
            string_capacity: 0,
            nested_type_name: String::new(),
        }];
    }
    msg.fields
        .iter()
        .map(|field| {
            let (base_id, string_capacity, nested_type_name) = match &field.ty.base {
                BaseType::Primitive(p) => (primitive_id(*p), 0, String::new()),
                BaseType::String { bound: None } => (field_type::STRING, 0, String::new()),
                BaseType::String { bound: Some(b) } => {
                    (field_type::BOUNDED_STRING, *b, String::new())
                }
                BaseType::Nested { name, .. } => (field_type::NESTED_TYPE, 0, name.to_string()),
            };
            let (offset, capacity) = match field.ty.array {
                ArrayKind::Single => (0, 0),
                ArrayKind::Fixed(n) => (field_type::ARRAY_OFFSET, n),
                ArrayKind::Bounded(n) => (field_type::BOUNDED_SEQUENCE_OFFSET, n),
                ArrayKind::Unbounded => (field_type::UNBOUNDED_SEQUENCE_OFFSET, 0),
            };
            HashField {
                name: field.name.clone(),
                type_id: base_id + offset,
                capacity,
                string_capacity,
                nested_type_name,
            }
        })
        .collect()
}

fn collect(registry: &Registry, name: &TypeName, into: &mut BTreeMap<String, Vec<HashField>>) {
    let key = name.to_string();
    if into.contains_key(&key) {
        return;
    }
    let fields = describe(registry, name);
    into.insert(key, fields.clone());
    for field in fields.iter().filter(|f| !f.nested_type_name.is_empty()) {
        collect(registry, &parse_full_name(&field.nested_type_name), into);
    }
}

fn parse_full_name(full: &str) -> TypeName {
    let mut parts = full.splitn(3, '/');
    let (p, k, n) = (
        parts.next().unwrap(),
        parts.next().unwrap(),
        parts.next().unwrap(),
    );
    TypeName::new(p, k, n)
}

fn struct_json(out: &mut String, type_name: &str, fields: &[HashField]) {
    write!(out, "{{\"type_name\": \"{type_name}\", \"fields\": [").unwrap();
    for (i, f) in fields.iter().enumerate() {
        if i > 0 {
            out.push_str(", ");
        }
        write!(
            out,
            "{{\"name\": \"{}\", \"type\": {{\"type_id\": {}, \"capacity\": {}, \
             \"string_capacity\": {}, \"nested_type_name\": \"{}\"}}}}",
            f.name, f.type_id, f.capacity, f.string_capacity, f.nested_type_name
        )
        .unwrap();
    }
    out.push_str("]}");
}

/// The JSON document that is hashed (exposed for tests and debugging).
pub fn hashed_json(registry: &Registry, root: &TypeName) -> String {
    let mut all = BTreeMap::new();
    collect(registry, root, &mut all);
    let root_key = root.to_string();
    let mut out = String::from("{\"type_description\": ");
    struct_json(&mut out, &root_key, &all[&root_key]);
    out.push_str(", \"referenced_type_descriptions\": [");
    for (i, (name, fields)) in all.iter().filter(|(n, _)| **n != root_key).enumerate() {
        if i > 0 {
            out.push_str(", ");
        }
        struct_json(&mut out, name, fields);
    }
    out.push_str("]}");
    out
}

/// `RIHS01_` + the lowercase hex SHA-256 of [`hashed_json`].
pub fn rihs01(registry: &Registry, root: &TypeName) -> String {
    let digest = Sha256::digest(hashed_json(registry, root).as_bytes());
    let mut hex = String::with_capacity(64);
    for byte in digest {
        write!(hex, "{byte:02x}").unwrap();
    }
    format!("RIHS01_{hex}")
}
