//! Shared by the tests and the examples (`msg_probe`, `fuzz_cdr`): random message instances
//! built from the static field descriptions, so every generated type is exercised the same way;
//! the CDR decoder fuzzer (`fuzz`).
#![allow(dead_code)]

pub mod fuzz;

use composuite_msgs::{
    ArrayKind, ElementType, FieldDescription, MessageVisitor, RosMessage, TypeDescription,
};
use rand::{Rng, RngCore};
use serde_json::{Map, Value};

/// Characters strings are drawn from: ASCII incl. quotes and backslash, and multi-byte UTF-8.
const STRING_CHARS: &[char] = &[
    'a', 'Z', '0', ' ', '"', '\\', '/', '#', '\n', '\t', 'é', 'ß', '漢', '字', '🤖',
];

/// A random JSON value of the given type (max `max_len` elements per unbounded sequence).
pub fn random_value(rng: &mut impl RngCore, desc: &TypeDescription, max_len: usize) -> Value {
    let mut object = Map::new();
    for field in desc.fields {
        object.insert(field.name.to_string(), random_field(rng, field, max_len));
    }
    Value::Object(object)
}

fn random_field(rng: &mut impl RngCore, field: &FieldDescription, max_len: usize) -> Value {
    let count = match field.array {
        ArrayKind::Single => return random_element(rng, &field.element, max_len),
        ArrayKind::Fixed(n) => n,
        ArrayKind::Bounded(n) => rng.random_range(0..=n),
        ArrayKind::Unbounded => rng.random_range(0..=max_len),
    };
    Value::Array(
        (0..count)
            .map(|_| random_element(rng, &field.element, max_len))
            .collect(),
    )
}

fn finite_f64(rng: &mut impl RngCore) -> f64 {
    match rng.random_range(0..8) {
        0 => 0.0,
        1 => -0.0,
        2 => f64::MIN_POSITIVE / 4.0, // subnormal
        3 => rng.random_range(-10.0..10.0),
        _ => loop {
            let v = f64::from_bits(rng.next_u64());
            if v.is_finite() {
                break v;
            }
        },
    }
}

fn finite_f32(rng: &mut impl RngCore) -> f32 {
    match rng.random_range(0..8) {
        0 => 0.0,
        1 => -0.0,
        2 => f32::MIN_POSITIVE / 4.0,
        3 => rng.random_range(-10.0..10.0),
        _ => loop {
            let v = f32::from_bits(rng.next_u32());
            if v.is_finite() {
                break v;
            }
        },
    }
}

fn random_element(rng: &mut impl RngCore, element: &ElementType, max_len: usize) -> Value {
    match element {
        ElementType::Bool => Value::Bool(rng.random()),
        ElementType::Byte | ElementType::Char | ElementType::UInt8 => rng.random::<u8>().into(),
        ElementType::Int8 => rng.random::<i8>().into(),
        ElementType::Int16 => rng.random::<i16>().into(),
        ElementType::UInt16 => rng.random::<u16>().into(),
        ElementType::Int32 => rng.random::<i32>().into(),
        ElementType::UInt32 => rng.random::<u32>().into(),
        ElementType::Int64 => rng.random::<i64>().into(),
        ElementType::UInt64 => rng.random::<u64>().into(),
        ElementType::Float32 => Value::from(finite_f32(rng) as f64),
        ElementType::Float64 => Value::from(finite_f64(rng)),
        ElementType::String { bound } => {
            let mut s = String::new();
            let chars = rng.random_range(0..=12);
            for _ in 0..chars {
                let c = STRING_CHARS[rng.random_range(0..STRING_CHARS.len())];
                if bound.is_some_and(|b| s.len() + c.len_utf8() > b) {
                    break;
                }
                s.push(c);
            }
            Value::String(s)
        }
        ElementType::Nested(desc) => random_value(rng, desc, max_len),
    }
}

/// A random typed instance of `T`.
pub fn random_message<T: RosMessage>(rng: &mut impl RngCore, max_len: usize) -> T {
    serde_json::from_value(random_value(rng, T::DESCRIPTION, max_len))
        .unwrap_or_else(|e| panic!("random value does not fit {}: {e}", T::ROS_NAME))
}

/// Every message type's ROS name.
pub fn message_names() -> Vec<&'static str> {
    struct Names(Vec<&'static str>);
    impl MessageVisitor for Names {
        fn visit<T: RosMessage>(&mut self) {
            self.0.push(T::ROS_NAME);
        }
    }
    let mut names = Names(Vec::new());
    composuite_msgs::visit_messages(&mut names);
    names.0
}

/// Lowercase hex of a byte buffer.
pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Bytes of a lowercase hex string.
pub fn unhex(text: &str) -> Result<Vec<u8>, String> {
    if !text.len().is_multiple_of(2) {
        return Err(format!("odd-length hex string ({} characters)", text.len()));
    }
    (0..text.len())
        .step_by(2)
        .map(|i| {
            u8::from_str_radix(&text[i..i + 2], 16).map_err(|e| format!("bad hex at {i}: {e}"))
        })
        .collect()
}
