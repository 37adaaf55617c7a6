//! CDR encoding of messages as ROS 2 puts them on the wire and in rosbag2 files: a 4-byte
//! encapsulation header (`00 01` little-endian / `00 00` big-endian, then two option bytes)
//! followed by the plain-CDR body.
//!
//! The body is written by `cdr-encoding`, the serializer `ros2-client`/RustDDS use, so what
//! these functions produce is what the nodes send. Decoding never panics: truncated input,
//! lengths pointing past the end, invalid UTF-8, bad booleans and bounded fields over their bound
//! are all errors.
//!
//! Nor does decoding allocate more than the input can hold. Before the body reaches the
//! decoder, one pass over it guided by the type's [`TypeDescription`] (no allocation) checks
//! every string and sequence length against the bytes left at that point: a string of L bytes
//! needs L, a sequence of N elements needs at least N times the element's smallest encoding. A
//! length of 2^32-1 is a [`CdrError::Truncated`] naming the field, the length and the bytes left,
//! before a single element is decoded. The pass reads exactly the bytes the decoder reads (the
//! same alignment), so it refuses only what the decoder would refuse later (the fuzz test checks
//! that on every input).

use std::fmt;

use byteorder::{BigEndian, LittleEndian};

use crate::{ArrayKind, BoundsError, ElementType, RosMessage, TypeDescription};

/// Encapsulation identifier of plain CDR, big-endian.
pub const CDR_BE: [u8; 2] = [0x00, 0x00];
/// Encapsulation identifier of plain CDR, little-endian (what ROS 2 on x86/ARM writes).
pub const CDR_LE: [u8; 2] = [0x00, 0x01];

/// Why a buffer could not be decoded (or a message encoded).
#[derive(Debug, Clone, PartialEq)]
pub enum CdrError {
    /// Shorter than the 4-byte encapsulation header.
    MissingHeader {
        /// Buffer length.
        len: usize,
    },
    /// The encapsulation is not plain CDR.
    UnsupportedEncapsulation {
        /// The two identifier bytes found.
        found: [u8; 2],
    },
    /// The body does not decode as the message type.
    Malformed {
        /// The type being decoded.
        type_name: &'static str,
        /// What the decoder reported.
        reason: String,
    },
    /// A field does not fit in the rest of the buffer: a string or sequence length read from
    /// the wire claims more bytes than are left (refused before anything is allocated for it),
    /// or the buffer ends inside a field.
    Truncated {
        /// The type being decoded.
        type_name: &'static str,
        /// Path of the field, e.g. `transforms[2].child_frame_id`.
        field: String,
        /// What did not fit.
        shortfall: Shortfall,
        /// Bytes needed at least from that point on (alignment padding included); for a string
        /// or sequence, from just after its length word.
        needed: u64,
        /// Bytes left in the body at that point.
        remaining: usize,
    },
    /// A bounded field is over its bound.
    Bounds {
        /// The type.
        type_name: &'static str,
        /// Which field.
        error: BoundsError,
    },
}

impl fmt::Display for CdrError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CdrError::MissingHeader { len } => {
                write!(
                    f,
                    "CDR buffer of {len} bytes is shorter than the 4-byte encapsulation header"
                )
            }
            CdrError::UnsupportedEncapsulation { found } => write!(
                f,
                "unsupported CDR encapsulation {:02x} {:02x}; valid: 00 00 (CDR big-endian), 00 01 (CDR little-endian)",
                found[0], found[1]
            ),
            CdrError::Malformed { type_name, reason } => {
                write!(f, "malformed {type_name}: {reason}")
            }
            CdrError::Truncated {
                type_name,
                field,
                shortfall,
                needed,
                remaining,
            } => match shortfall {
                Shortfall::Sequence { len, element_size } => write!(
                    f,
                    "malformed {type_name}: sequence `{field}` declares {len} elements of at least {element_size} bytes each ({needed} bytes), but only {remaining} bytes are left"
                ),
                Shortfall::String { len } => write!(
                    f,
                    "malformed {type_name}: string `{field}` declares {len} bytes, but only {remaining} bytes are left"
                ),
                Shortfall::Value => write!(
                    f,
                    "malformed {type_name}: the buffer ends inside `{field}`, which needs {needed} bytes (alignment included), but only {remaining} bytes are left"
                ),
            },
            CdrError::Bounds { type_name, error } => write!(f, "{type_name}: {error}"),
        }
    }
}

/// What did not fit in a [`CdrError::Truncated`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shortfall {
    /// A sequence's length word declares `len` elements, each at least `element_size` bytes.
    Sequence {
        /// Elements declared.
        len: u32,
        /// The smallest encoding of one element, in bytes.
        element_size: usize,
    },
    /// A string's length word declares `len` bytes (its terminating NUL included).
    String {
        /// Bytes declared.
        len: u32,
    },
    /// The buffer ends inside a number, a boolean, a length word or a fixed-size array.
    Value,
}

impl std::error::Error for CdrError {}

/// Encode `msg` as little-endian CDR with its encapsulation header. Fails only when a bounded
/// field is over its bound.
pub fn encode<T: RosMessage>(msg: &T) -> Result<Vec<u8>, CdrError> {
    msg.check_bounds().map_err(|error| CdrError::Bounds {
        type_name: T::ROS_NAME,
        error,
    })?;
    let body = cdr_encoding::to_vec::<T, LittleEndian>(msg).map_err(|e| CdrError::Malformed {
        type_name: T::ROS_NAME,
        reason: e.to_string(),
    })?;
    let mut out = Vec::with_capacity(4 + body.len());
    out.extend_from_slice(&CDR_LE);
    out.extend_from_slice(&[0, 0]);
    out.extend_from_slice(&body);
    Ok(out)
}

/// Decode a CDR buffer (with its encapsulation header) as `T`. Trailing bytes after the message
/// (alignment padding some writers add) are ignored.
pub fn decode<T: RosMessage>(bytes: &[u8]) -> Result<T, CdrError> {
    if bytes.len() < 4 {
        return Err(CdrError::MissingHeader { len: bytes.len() });
    }
    let body = &bytes[4..];
    let malformed = |e: cdr_encoding::Error| CdrError::Malformed {
        type_name: T::ROS_NAME,
        reason: e.to_string(),
    };
    let big_endian = match [bytes[0], bytes[1]] {
        CDR_LE => false,
        CDR_BE => true,
        found => return Err(CdrError::UnsupportedEncapsulation { found }),
    };
    check_lengths(T::DESCRIPTION, body, big_endian).map_err(|short| CdrError::Truncated {
        type_name: T::ROS_NAME,
        field: short.field,
        shortfall: short.shortfall,
        needed: short.needed,
        remaining: short.remaining,
    })?;
    let msg: T = if big_endian {
        cdr_encoding::from_bytes::<T, BigEndian>(body)
            .map_err(malformed)?
            .0
    } else {
        cdr_encoding::from_bytes::<T, LittleEndian>(body)
            .map_err(malformed)?
            .0
    };
    msg.check_bounds().map_err(|error| CdrError::Bounds {
        type_name: T::ROS_NAME,
        error,
    })?;
    Ok(msg)
}

/// A field that does not fit (see [`CdrError::Truncated`]); the path is built on the way out.
struct Short {
    field: String,
    shortfall: Shortfall,
    needed: u64,
    remaining: usize,
}

impl Short {
    /// Prefix the path with the enclosing field (the same path syntax as [`BoundsError`]).
    fn within(mut self, outer: &str) -> Short {
        self.field = if self.field.is_empty() {
            outer.to_string()
        } else if self.field.starts_with('[') {
            format!("{outer}{}", self.field)
        } else {
            format!("{outer}.{}", self.field)
        };
        self
    }

    /// Prefix the path with an element index.
    fn at(mut self, index: usize) -> Short {
        self.field = if self.field.is_empty() || self.field.starts_with('[') {
            format!("[{index}]{}", self.field)
        } else {
            format!("[{index}].{}", self.field)
        };
        self
    }
}

/// Walks a CDR body as `desc` lays it out, reading only lengths, and checks that every field,
/// string and sequence fits in the bytes left. Reads exactly what `cdr-encoding`'s decoder reads:
/// numbers aligned to their size relative to the body's start, booleans and octets unaligned,
/// strings and sequences as a 4-aligned u32 length then their contents, fixed arrays without a
/// length, nested messages inline. Allocates nothing unless it fails.
fn check_lengths(desc: &TypeDescription, body: &[u8], big_endian: bool) -> Result<(), Short> {
    Walk {
        body,
        pos: 0,
        big_endian,
    }
    .message(desc)
}

struct Walk<'a> {
    body: &'a [u8],
    pos: usize,
    big_endian: bool,
}

/// Size (= alignment) of a primitive, `None` for strings and messages.
fn primitive_size(element: &ElementType) -> Option<usize> {
    match element {
        ElementType::Bool
        | ElementType::Byte
        | ElementType::Char
        | ElementType::Int8
        | ElementType::UInt8 => Some(1),
        ElementType::Int16 | ElementType::UInt16 => Some(2),
        ElementType::Int32 | ElementType::UInt32 | ElementType::Float32 => Some(4),
        ElementType::Int64 | ElementType::UInt64 | ElementType::Float64 => Some(8),
        ElementType::String { .. } | ElementType::Nested(_) => None,
    }
}

/// The fewest bytes one element takes on the wire, padding not counted: a lower bound on what
/// each element of a sequence consumes. At least 1 for every ROS type (no zero-size arrays; an
/// empty message has a placeholder octet).
fn min_size(element: &ElementType) -> usize {
    match element {
        ElementType::String { .. } => 4,
        ElementType::Nested(desc) => desc
            .fields
            .iter()
            .map(|field| match field.array {
                ArrayKind::Single => min_size(&field.element),
                ArrayKind::Fixed(n) => n.saturating_mul(min_size(&field.element)),
                ArrayKind::Bounded(_) | ArrayKind::Unbounded => 4,
            })
            .fold(0, usize::saturating_add),
        primitive => primitive_size(primitive).unwrap_or(1),
    }
}

impl Walk<'_> {
    fn remaining(&self) -> usize {
        self.body.len() - self.pos
    }

    fn padding(&self, align: usize) -> usize {
        (align - self.pos % align) % align
    }

    /// Skips the padding to `align` and then `size` bytes; returns where those start.
    fn take(&mut self, align: usize, size: usize) -> Result<usize, Short> {
        let needed = self.padding(align).saturating_add(size);
        if needed > self.remaining() {
            return Err(Short {
                field: String::new(),
                shortfall: Shortfall::Value,
                needed: needed as u64,
                remaining: self.remaining(),
            });
        }
        let start = self.pos + self.padding(align);
        self.pos += needed;
        Ok(start)
    }

    /// A string or sequence length word.
    fn length(&mut self) -> Result<u32, Short> {
        let at = self.take(4, 4)?;
        let word: [u8; 4] = self.body[at..at + 4].try_into().expect("4 bytes");
        Ok(if self.big_endian {
            u32::from_be_bytes(word)
        } else {
            u32::from_le_bytes(word)
        })
    }

    fn message(&mut self, desc: &TypeDescription) -> Result<(), Short> {
        for field in desc.fields {
            self.field(&field.element, field.array)
                .map_err(|short| short.within(field.name))?;
        }
        Ok(())
    }

    fn field(&mut self, element: &ElementType, array: ArrayKind) -> Result<(), Short> {
        match array {
            ArrayKind::Single => self.element(element),
            ArrayKind::Fixed(n) => self.elements(element, n),
            ArrayKind::Bounded(_) | ArrayKind::Unbounded => {
                let len = self.length()?;
                let element_size = min_size(element);
                // A run of primitives is padded once, before its first element.
                let padding = match primitive_size(element) {
                    Some(size) if len > 0 => self.padding(size),
                    _ => 0,
                };
                let needed = u64::from(len) * element_size as u64 + padding as u64;
                if needed > self.remaining() as u64 {
                    return Err(Short {
                        field: String::new(),
                        shortfall: Shortfall::Sequence { len, element_size },
                        needed,
                        remaining: self.remaining(),
                    });
                }
                self.elements(element, len as usize)
            }
        }
    }

    /// `count` consecutive elements.
    fn elements(&mut self, element: &ElementType, count: usize) -> Result<(), Short> {
        if count == 0 {
            return Ok(());
        }
        if let Some(size) = primitive_size(element) {
            return self.take(size, size.saturating_mul(count)).map(|_| ());
        }
        for index in 0..count {
            self.element(element).map_err(|short| short.at(index))?;
        }
        Ok(())
    }

    fn element(&mut self, element: &ElementType) -> Result<(), Short> {
        match element {
            ElementType::Nested(desc) => self.message(desc),
            ElementType::String { .. } => {
                let len = self.length()?;
                if len as usize > self.remaining() {
                    return Err(Short {
                        field: String::new(),
                        shortfall: Shortfall::String { len },
                        needed: u64::from(len),
                        remaining: self.remaining(),
                    });
                }
                self.pos += len as usize;
                Ok(())
            }
            primitive => {
                let size = primitive_size(primitive).unwrap_or(1);
                self.take(size, size).map(|_| ())
            }
        }
    }
}

/// Serde adapter for fixed-size arrays `T[N]`: N elements with no length prefix (a CDR array),
/// for any N (serde's own array support stops at 32).
pub mod fixed_array {
    use std::fmt;
    use std::marker::PhantomData;

    use serde::de::{Deserialize, Deserializer, Error, SeqAccess, Visitor};
    use serde::ser::{Serialize, SerializeTuple, Serializer};

    /// Serialize as a tuple of N elements.
    pub fn serialize<S: Serializer, T: Serialize, const N: usize>(
        array: &[T; N],
        serializer: S,
    ) -> Result<S::Ok, S::Error> {
        let mut tuple = serializer.serialize_tuple(N)?;
        for element in array {
            tuple.serialize_element(element)?;
        }
        tuple.end()
    }

    /// Deserialize a tuple of exactly N elements.
    pub fn deserialize<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(
        deserializer: D,
    ) -> Result<[T; N], D::Error> {
        struct ArrayVisitor<T, const N: usize>(PhantomData<T>);
        impl<'de, T: Deserialize<'de>, const N: usize> Visitor<'de> for ArrayVisitor<T, N> {
            type Value = [T; N];
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "an array of {N} elements")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<[T; N], A::Error> {
                let mut elements = Vec::with_capacity(N);
                while elements.len() < N {
                    match seq.next_element()? {
                        Some(element) => elements.push(element),
                        None => return Err(A::Error::invalid_length(elements.len(), &self)),
                    }
                }
                // A self-describing format (JSON) may offer more; CDR never does.
                if seq.next_element::<serde::de::IgnoredAny>()?.is_some() {
                    return Err(A::Error::invalid_length(N + 1, &self));
                }
                elements
                    .try_into()
                    .map_err(|_| A::Error::custom("array length changed"))
            }
        }
        deserializer.deserialize_tuple(N, ArrayVisitor::<T, N>(PhantomData))
    }
}
