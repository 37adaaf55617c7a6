//! The CDR decoder fuzzer, shared by `tests/fuzz.rs` (a short run in CI) and
//! `examples/fuzz_cdr.rs` (the benchmark run, 1 M inputs per type).
//!
//! For every message type of the crate — `visit_messages` lists them all, service requests,
//! responses and events included — it feeds [`cdr::decode`] a deterministic (seeded) stream of
//! (a) valid samples, little- and big-endian, mutated by bit flips, byte overwrites, truncation,
//! extension, insertions and deletions, splices of other samples and length words of
//! 0xFFFFFFFF (and other extreme lengths) at 4-aligned offsets, and (b) random byte strings. Per
//! input it checks that decoding does not panic, that no single allocation made while decoding
//! exceeds [`allocation_bound`] of the input's length (measured by [`CountingAlloc`], which the
//! binary must install as its `#[global_allocator]`), and that `cdr::decode` agrees with plain
//! `cdr-encoding` (what `ros2-client` uses to decode received messages), whose allocations are
//! held to the same bound.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::fmt;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::time::{Duration, Instant};

use byteorder::{BigEndian, LittleEndian};
use composuite_msgs::cdr::{self, CdrError};
use composuite_msgs::{ArrayKind, ElementType, MessageVisitor, RosMessage, TypeDescription};
use rand::{Rng, RngCore, SeedableRng};

type Rng8 = rand_chacha::ChaCha8Rng;

/// The system allocator, recording per thread the largest single allocation (or reallocation)
/// requested. Install it with `#[global_allocator]` in the binary that fuzzes.
pub struct CountingAlloc;

thread_local! {
    // `const` and no destructor: reading it never allocates, so the allocator may use it.
    static LARGEST: Cell<usize> = const { Cell::new(0) };
}

fn record(size: usize) {
    // `try_with`: allocations made while the thread is torn down are not recorded.
    let _ = LARGEST.try_with(|largest| {
        if size > largest.get() {
            largest.set(size);
        }
    });
}

// SAFETY: every call is forwarded unchanged to `System`; recording touches no allocator state.
unsafe impl GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        record(layout.size());
        // SAFETY: the caller's contract, passed on.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        record(layout.size());
        // SAFETY: the caller's contract, passed on.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        record(new_size);
        // SAFETY: the caller's contract, passed on.
        unsafe { System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the caller's contract, passed on.
        unsafe { System.dealloc(ptr, layout) }
    }
}

/// Runs `f` and returns its result with the largest single allocation it requested on this
/// thread (0 if none).
pub fn largest_allocation<R>(f: impl FnOnce() -> R) -> (R, usize) {
    LARGEST.with(|largest| largest.set(0));
    let result = f();
    (result, LARGEST.with(Cell::get))
}

/// Panics unless [`CountingAlloc`] is the global allocator (else every measurement reads 0).
pub fn assert_allocator_installed() {
    let (_, largest) = largest_allocation(|| std::hint::black_box(Vec::<u8>::with_capacity(12345)));
    assert!(
        largest >= 12345,
        "CountingAlloc is not the #[global_allocator] of this binary"
    );
}

/// Bytes per input byte in [`allocation_bound`].
pub const BOUND_PER_INPUT_BYTE: usize = 64;
/// Constant part of [`allocation_bound`].
pub const BOUND_CONSTANT: usize = 64 * 1024;

/// The largest single allocation decoding `input_len` bytes may request: 64 · len + 64 KiB.
///
/// Why that suffices for a correct decoder (`tests/fuzz.rs::allocation_bound_covers_every_type`
/// computes the constants from the generated types): the only allocations sized by the data are
/// a string's bytes (at most the input), a fixed array's staging `Vec` (N elements the input must
/// hold) and a sequence's `Vec`, grown by doubling from a minimum of 4 elements (8 for bytes) as
/// elements are decoded, so its buffer holds at most max(2·N, 4) elements of S bytes where N ≤
/// len / M, M the element's smallest encoding (≥ 1 byte). With ρ = max S/M over all element types
/// (6.15 today: a `String` or `Vec` is 24 bytes in memory, its length word 4 on the wire) that is
/// at most 2·ρ·len + 4·S_max, plus error messages (< 1 KiB). The bound leaves at least 4× headroom
/// on both parts (S_max is 856 bytes today). An allocation driven by a length the input cannot
/// hold (2^32-1 elements → gigabytes) breaks it at once.
pub fn allocation_bound(input_len: usize) -> usize {
    BOUND_PER_INPUT_BYTE
        .saturating_mul(input_len)
        .saturating_add(BOUND_CONSTANT)
}

/// The fewest bytes an element of this type occupies on the wire (alignment padding not
/// counted): a lower bound on what each element of a sequence consumes.
pub fn min_encoded_size(element: &ElementType) -> usize {
    match element {
        ElementType::Bool
        | ElementType::Byte
        | ElementType::Char
        | ElementType::Int8
        | ElementType::UInt8 => 1,
        ElementType::Int16 | ElementType::UInt16 => 2,
        ElementType::Int32 | ElementType::UInt32 | ElementType::Float32 => 4,
        ElementType::Int64 | ElementType::UInt64 | ElementType::Float64 => 8,
        ElementType::String { .. } => 4,
        ElementType::Nested(desc) => min_message_size(desc),
    }
}

/// [`min_encoded_size`] of a whole message.
pub fn min_message_size(desc: &TypeDescription) -> usize {
    desc.fields
        .iter()
        .map(|field| match field.array {
            ArrayKind::Single => min_encoded_size(&field.element),
            ArrayKind::Fixed(n) => n * min_encoded_size(&field.element),
            ArrayKind::Bounded(_) | ArrayKind::Unbounded => 4,
        })
        .sum()
}

/// What to run.
#[derive(Debug, Clone)]
pub struct Config {
    /// Base seed; each type's stream is seeded from it and the type's name.
    pub seed: u64,
    /// Inputs per type.
    pub inputs_per_type: u64,
    /// Valid samples per type that mutations start from.
    pub samples: usize,
    /// Only types whose ROS name contains this.
    pub only: Option<String>,
}

/// What one type's run saw.
#[derive(Debug, Clone, Default)]
pub struct TypeStats {
    /// `pkg/msg/Name`.
    pub type_name: &'static str,
    /// Inputs decoded.
    pub inputs: u64,
    /// Of those, mutated valid samples (the rest are random bytes).
    pub mutated: u64,
    /// Inputs that decoded.
    pub ok: u64,
    /// Inputs that were refused with an error.
    pub errors: u64,
    /// Of the errors, those refused as a length or field that the buffer cannot hold.
    pub truncated: u64,
    /// Largest single allocation while `cdr::decode` ran, in bytes.
    pub max_alloc: usize,
    /// Length of the input that made it.
    pub max_alloc_input_len: usize,
    /// Largest single allocation while plain `cdr-encoding` decoded the same inputs.
    pub max_alloc_raw: usize,
    /// Longest input.
    pub longest_input: usize,
    /// Wall time of the whole run of this type (generation and both decoders).
    pub elapsed: Duration,
}

impl TypeStats {
    /// Inputs per second over the whole run of this type.
    pub fn inputs_per_second(&self) -> f64 {
        self.inputs as f64 / self.elapsed.as_secs_f64().max(1e-9)
    }
}

/// A property violated by one input, with what it takes to reproduce it.
#[derive(Debug)]
pub struct Failure {
    /// The type being decoded.
    pub type_name: &'static str,
    /// Index of the input in the type's stream (`None`: while building the valid samples).
    pub input_index: Option<u64>,
    /// The input.
    pub input: Vec<u8>,
    /// What went wrong.
    pub what: String,
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let hex: String = self.input.iter().map(|b| format!("{b:02x}")).collect();
        write!(
            f,
            "{}: input {:?} ({} bytes): {}\ninput: {hex}",
            self.type_name,
            self.input_index,
            self.input.len(),
            self.what
        )
    }
}

/// Fuzzes every message type (service halves included), in name order, calling `report` after
/// each type. Stops at the first failure.
pub fn fuzz_all(
    config: &Config,
    report: &mut dyn FnMut(&TypeStats),
) -> Result<Vec<TypeStats>, Failure> {
    struct Each<'a> {
        config: &'a Config,
        report: &'a mut dyn FnMut(&TypeStats),
        done: Vec<TypeStats>,
        failure: Option<Failure>,
    }
    impl MessageVisitor for Each<'_> {
        fn visit<T: RosMessage>(&mut self) {
            let wanted = self
                .config
                .only
                .as_deref()
                .is_none_or(|only| T::ROS_NAME.contains(only));
            if self.failure.is_some() || !wanted {
                return;
            }
            match fuzz_type::<T>(self.config) {
                Ok(stats) => {
                    (self.report)(&stats);
                    self.done.push(stats);
                }
                Err(failure) => self.failure = Some(failure),
            }
        }
    }
    let mut each = Each {
        config,
        report,
        done: Vec::new(),
        failure: None,
    };
    composuite_msgs::visit_messages(&mut each);
    match each.failure {
        Some(failure) => Err(failure),
        None => Ok(each.done),
    }
}

/// FNV-1a: a stable per-type seed, independent of the order types are visited in.
fn fnv1a(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |hash, byte| {
        (hash ^ u64::from(byte)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// Fuzzes one type.
pub fn fuzz_type<T: RosMessage>(config: &Config) -> Result<TypeStats, Failure> {
    let mut rng = Rng8::seed_from_u64(config.seed ^ fnv1a(T::ROS_NAME));
    let samples = valid_samples::<T>(&mut rng, config.samples.max(1))?;
    let mut stats = TypeStats {
        type_name: T::ROS_NAME,
        ..TypeStats::default()
    };
    let start = Instant::now();
    let mut input = Vec::new();
    for index in 0..config.inputs_per_type {
        input.clear();
        if rng.random_bool(0.75) {
            mutate(&mut rng, &samples, &mut input);
            stats.mutated += 1;
        } else {
            random_bytes(&mut rng, &mut input);
        }
        check::<T>(&input, &mut stats).map_err(|what| Failure {
            type_name: T::ROS_NAME,
            input_index: Some(index),
            input: input.clone(),
            what,
        })?;
    }
    stats.elapsed = start.elapsed();
    Ok(stats)
}

/// Encoded random instances of `T` (the default instance first), half little-, half big-endian;
/// each must decode back to itself.
fn valid_samples<T: RosMessage>(rng: &mut Rng8, count: usize) -> Result<Vec<Vec<u8>>, Failure> {
    let mut samples = Vec::with_capacity(count);
    for index in 0..count {
        let msg: T = if index == 0 {
            T::default()
        } else {
            let max_len = rng.random_range(0..=6);
            super::random_message(rng, max_len)
        };
        let bytes = if index % 2 == 0 {
            cdr::encode(&msg).expect("random instances respect their bounds")
        } else {
            let mut bytes = vec![cdr::CDR_BE[0], cdr::CDR_BE[1], 0, 0];
            bytes.extend(cdr_encoding::to_vec::<T, BigEndian>(&msg).expect("encodes"));
            bytes
        };
        match cdr::decode::<T>(&bytes) {
            Ok(back) if back == msg => samples.push(bytes),
            other => {
                return Err(Failure {
                    type_name: T::ROS_NAME,
                    input_index: None,
                    input: bytes,
                    what: format!("a valid sample does not decode to itself: {other:?}"),
                });
            }
        }
    }
    Ok(samples)
}

/// Writes `word` at `offset` in the byte order of the sample's encapsulation header.
fn put_word(input: &mut [u8], offset: usize, word: u32) {
    let bytes = if input.get(1) == Some(&cdr::CDR_BE[1]) {
        word.to_be_bytes()
    } else {
        word.to_le_bytes()
    };
    input[offset..offset + 4].copy_from_slice(&bytes);
}

/// A random 4-aligned offset of the body (the body starts at byte 4, and CDR aligns relative to
/// it) where a whole word fits, if any.
fn aligned_word_offset(rng: &mut Rng8, len: usize) -> Option<usize> {
    (len >= 8).then(|| 4 * rng.random_range(1..=(len - 4) / 4))
}

/// A valid sample with 1–4 mutations.
fn mutate(rng: &mut Rng8, samples: &[Vec<u8>], out: &mut Vec<u8>) {
    out.extend_from_slice(&samples[rng.random_range(0..samples.len())]);
    for _ in 0..rng.random_range(1..=4) {
        let len = out.len();
        match rng.random_range(0..10) {
            // Flip one bit.
            0 if len > 0 => {
                let at = rng.random_range(0..len);
                out[at] ^= 1 << rng.random_range(0..8);
            }
            // Overwrite one byte with 0x00, 0xFF or a random value.
            1 if len > 0 => {
                let at = rng.random_range(0..len);
                out[at] = match rng.random_range(0..3) {
                    0 => 0x00,
                    1 => 0xFF,
                    _ => rng.random(),
                };
            }
            // Truncate.
            2 => out.truncate(rng.random_range(0..=len)),
            // Extend by random bytes or zeros.
            3 => {
                let extra = rng.random_range(1..=32);
                let zeros = rng.random_bool(0.5);
                out.extend((0..extra).map(|_| if zeros { 0 } else { rng.random::<u8>() }));
            }
            // A length of 2^32-1 at a 4-aligned offset.
            4 => {
                if let Some(at) = aligned_word_offset(rng, len) {
                    out[at..at + 4].copy_from_slice(&[0xFF; 4]);
                }
            }
            // Another extreme or plausible length word, in the sample's byte order.
            5 => {
                if let Some(at) = aligned_word_offset(rng, len) {
                    let word = match rng.random_range(0..7) {
                        0 => 0x7FFF_FFFF,
                        1 => 0x8000_0000,
                        2 => 0x0001_0000,
                        3 => len as u32,
                        4 => (len as u32).wrapping_sub(at as u32),
                        5 => rng.random(),
                        _ => rng.random_range(0..=16),
                    };
                    put_word(out, at, word);
                }
            }
            // Insert random bytes (shifts everything after out of alignment).
            6 => {
                let at = rng.random_range(0..=len);
                let count = rng.random_range(1..=8);
                let bytes: Vec<u8> = (0..count).map(|_| rng.random()).collect();
                out.splice(at..at, bytes);
            }
            // Delete a range.
            7 if len > 0 => {
                let from = rng.random_range(0..len);
                let to = rng.random_range(from..=len.min(from + 16));
                out.drain(from..to);
            }
            // Splice: keep a prefix, continue with another sample's tail.
            8 => {
                let other = &samples[rng.random_range(0..samples.len())];
                let cut = rng.random_range(0..=len);
                let from = rng.random_range(0..=other.len());
                out.truncate(cut);
                out.extend_from_slice(&other[from..]);
            }
            // The encapsulation header: the other byte order, or random options.
            9 if len >= 4 => {
                if rng.random_bool(0.5) {
                    out[1] ^= 1;
                } else {
                    let at = rng.random_range(0..4);
                    out[at] = rng.random();
                }
            }
            _ => {}
        }
    }
}

/// Random bytes, mostly after a valid encapsulation header (else nearly all are refused there).
fn random_bytes(rng: &mut Rng8, out: &mut Vec<u8>) {
    let len = match rng.random_range(0..20) {
        0 => rng.random_range(512..4096),
        1..=5 => rng.random_range(64..512),
        _ => rng.random_range(0..64),
    };
    out.resize(len, 0);
    match rng.random_range(0..3) {
        0 => rng.fill_bytes(out),
        // Few distinct values: lengths are either tiny or huge, booleans often valid.
        1 => {
            for byte in out.iter_mut() {
                *byte = [0x00, 0x01, 0x02, 0xFF][rng.random_range(0..4)];
            }
        }
        // Mostly zeros: empty strings and sequences, so decoding gets deep.
        _ => {
            for byte in out.iter_mut() {
                if rng.random_bool(0.1) {
                    *byte = rng.random();
                }
            }
        }
    }
    if len >= 4 && rng.random_bool(0.9) {
        let id = if rng.random_bool(0.5) {
            cdr::CDR_LE
        } else {
            cdr::CDR_BE
        };
        out[..4].copy_from_slice(&[id[0], id[1], 0, 0]);
    }
}

/// Plain `cdr-encoding`, as `ros2-client` decodes what it receives (no bounds check).
fn raw_decode<T: RosMessage>(bytes: &[u8]) -> Result<T, String> {
    if bytes.len() < 4 {
        return Err("no header".into());
    }
    let body = &bytes[4..];
    match [bytes[0], bytes[1]] {
        cdr::CDR_LE => cdr_encoding::from_bytes::<T, LittleEndian>(body),
        cdr::CDR_BE => cdr_encoding::from_bytes::<T, BigEndian>(body),
        _ => return Err("not plain CDR".into()),
    }
    .map(|(msg, _)| msg)
    .map_err(|e| e.to_string())
}

fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "(non-string panic payload)".into())
}

/// Decodes one input both ways and checks the properties.
fn check<T: RosMessage>(input: &[u8], stats: &mut TypeStats) -> Result<(), String> {
    let bound = allocation_bound(input.len());
    let (ours, largest) = catch_unwind(AssertUnwindSafe(|| {
        largest_allocation(|| cdr::decode::<T>(input))
    }))
    .map_err(|panic| format!("cdr::decode panicked: {}", panic_text(&*panic)))?;
    let (raw, largest_raw) = catch_unwind(AssertUnwindSafe(|| {
        largest_allocation(|| raw_decode::<T>(input))
    }))
    .map_err(|panic| format!("cdr-encoding panicked: {}", panic_text(&*panic)))?;

    stats.inputs += 1;
    stats.longest_input = stats.longest_input.max(input.len());
    if largest > stats.max_alloc {
        stats.max_alloc = largest;
        stats.max_alloc_input_len = input.len();
    }
    stats.max_alloc_raw = stats.max_alloc_raw.max(largest_raw);
    if largest > bound {
        return Err(format!(
            "cdr::decode allocated {largest} bytes at once, over the bound {bound} ({:?})",
            ours.err()
        ));
    }
    if largest_raw > bound {
        return Err(format!(
            "cdr-encoding allocated {largest_raw} bytes at once, over the bound {bound} ({:?})",
            raw.err()
        ));
    }
    match (&ours, &raw) {
        (Ok(_), _) => stats.ok += 1,
        (Err(error), _) => {
            stats.errors += 1;
            if matches!(error, CdrError::Truncated { .. }) {
                stats.truncated += 1;
            }
        }
    }
    // The same verdict as plain cdr-encoding, except that bounded fields are checked on top.
    match (ours, raw) {
        (Ok(_), Err(e)) => Err(format!(
            "cdr::decode accepted what cdr-encoding refuses: {e}"
        )),
        (Err(CdrError::Bounds { .. }), Ok(_)) => Ok(()),
        (Err(e), Ok(_)) => Err(format!(
            "cdr::decode refused what cdr-encoding accepts: {e}"
        )),
        _ => Ok(()),
    }
}
