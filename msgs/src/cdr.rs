//! CDR encoding of messages as ROS 2 puts them on the wire and in rosbag2 files: a 4-byte
//! encapsulation header (`00 01` little-endian / `00 00` big-endian, then two option bytes)
//! followed by the plain-CDR body.
//!
//! The body is written by `cdr-encoding`, the serializer `ros2-client`/RustDDS use, so what
//! these functions produce is what the nodes send. Decoding never panics: truncated input,
//! lengths pointing past the end, invalid UTF-8, bad booleans and bounded fields over their bound
//! are all errors.

use std::fmt;

use byteorder::{BigEndian, LittleEndian};

use crate::{BoundsError, RosMessage};

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
            CdrError::Bounds { type_name, error } => write!(f, "{type_name}: {error}"),
        }
    }
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
    let msg: T = match [bytes[0], bytes[1]] {
        CDR_LE => {
            cdr_encoding::from_bytes::<T, LittleEndian>(body)
                .map_err(malformed)?
                .0
        }
        CDR_BE => {
            cdr_encoding::from_bytes::<T, BigEndian>(body)
                .map_err(malformed)?
                .0
        }
        found => return Err(CdrError::UnsupportedEncapsulation { found }),
    };
    msg.check_bounds().map_err(|error| CdrError::Bounds {
        type_name: T::ROS_NAME,
        error,
    })?;
    Ok(msg)
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
