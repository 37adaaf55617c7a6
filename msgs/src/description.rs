//! A static description of each message's fields, for tools that handle any message generically
//! (random instances in tests, recorders, introspection).

use std::fmt;

/// The fields of one message type, in wire order.
#[derive(Debug)]
pub struct TypeDescription {
    /// `pkg/msg/Name`.
    pub ros_name: &'static str,
    /// Fields in wire order.
    pub fields: &'static [FieldDescription],
}

/// One field of a message.
#[derive(Debug)]
pub struct FieldDescription {
    /// Field name as in the `.msg` file.
    pub name: &'static str,
    /// Element type.
    pub element: ElementType,
    /// Array-ness.
    pub array: ArrayKind,
}

/// The element type of a field.
#[derive(Debug)]
#[allow(missing_docs)]
pub enum ElementType {
    Bool,
    Byte,
    Char,
    Int8,
    UInt8,
    Int16,
    UInt16,
    Int32,
    UInt32,
    Int64,
    UInt64,
    Float32,
    Float64,
    /// A UTF-8 string, optionally bounded (bytes).
    String {
        /// Maximum length in bytes, if bounded.
        bound: Option<usize>,
    },
    /// Another message.
    Nested(&'static TypeDescription),
}

/// Array-ness of a field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArrayKind {
    /// One value.
    Single,
    /// Exactly N values (no length on the wire).
    Fixed(usize),
    /// At most N values.
    Bounded(usize),
    /// Any number of values.
    Unbounded,
}

/// A bounded string or sequence holds more than its bound allows.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BoundsError {
    /// Field path, e.g. `parts[3].name`.
    pub path: String,
    /// Actual length (bytes for strings, elements for sequences).
    pub len: usize,
    /// The bound.
    pub bound: usize,
}

impl BoundsError {
    /// `Err` when `len > bound`.
    pub fn check(path: &str, len: usize, bound: usize) -> Result<(), BoundsError> {
        if len > bound {
            Err(BoundsError {
                path: path.to_string(),
                len,
                bound,
            })
        } else {
            Ok(())
        }
    }

    /// Prefix the path with the enclosing field.
    pub fn within(mut self, outer: &str) -> BoundsError {
        self.path = match (outer.is_empty(), self.path.is_empty()) {
            (true, _) => self.path,
            (false, true) => outer.to_string(),
            (false, false) if self.path.starts_with('[') => format!("{outer}{}", self.path),
            (false, false) => format!("{outer}.{}", self.path),
        };
        self
    }
}

impl fmt::Display for BoundsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "field `{}` has length {}, more than its bound {}",
            self.path, self.len, self.bound
        )
    }
}

impl std::error::Error for BoundsError {}
