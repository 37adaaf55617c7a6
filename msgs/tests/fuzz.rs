//! Fuzzes every CDR decoder of the crate (the CI-sized run; `examples/fuzz_cdr.rs` is the
//! 1 M-inputs-per-type run of the same generator, `tests/support/fuzz.rs`): no panic, no single
//! allocation over 64 bytes per input byte + 64 KiB, the same verdict as plain `cdr-encoding`;
//! and lengths of 2^32-1 are refused before anything is allocated for them.

mod support;

use composuite_msgs::cdr::{self, CdrError, Shortfall};
use composuite_msgs::{ElementType, MessageVisitor, RosMessage, RosService, ServiceVisitor};
use support::fuzz;

#[global_allocator]
static ALLOCATOR: fuzz::CountingAlloc = fuzz::CountingAlloc;

/// Inputs per type in CI: 72 types x 3000, each decoded twice (ours and plain cdr-encoding),
/// a few seconds in the dev profile.
const CI_INPUTS_PER_TYPE: u64 = 3000;

#[test]
fn every_type_survives_mutated_and_random_inputs() {
    fuzz::assert_allocator_installed();
    let config = fuzz::Config {
        seed: 0x5eed,
        inputs_per_type: CI_INPUTS_PER_TYPE,
        samples: 32,
        only: None,
    };
    let all = fuzz::fuzz_all(&config, &mut |_| {}).unwrap_or_else(|failure| panic!("{failure}"));

    // Every message type, and both halves of every service, were fuzzed.
    let fuzzed: Vec<&str> = all.iter().map(|s| s.type_name).collect();
    assert_eq!(fuzzed, support::message_names());
    struct Halves(Vec<&'static str>);
    impl ServiceVisitor for Halves {
        fn visit<S: RosService>(&mut self) {
            self.0.push(<S::Request as RosMessage>::ROS_NAME);
            self.0.push(<S::Response as RosMessage>::ROS_NAME);
        }
    }
    let mut halves = Halves(Vec::new());
    composuite_msgs::visit_services(&mut halves);
    assert!(!halves.0.is_empty());
    for half in halves.0 {
        assert!(fuzzed.contains(&half), "service half {half} not fuzzed");
    }

    for stats in &all {
        assert_eq!(stats.inputs, CI_INPUTS_PER_TYPE);
        // Both outcomes are exercised: the mutations keep many inputs decodable.
        assert!(
            stats.ok >= CI_INPUTS_PER_TYPE / 20 && stats.errors >= CI_INPUTS_PER_TYPE / 20,
            "{}: {} decoded, {} errors",
            stats.type_name,
            stats.ok,
            stats.errors
        );
        assert!(stats.truncated > 0, "{}", stats.type_name);
        eprintln!(
            "{:<42} {} decoded, {} errors ({} truncated), max alloc {} B (plain cdr-encoding {} B), {:.0} inputs/s",
            stats.type_name,
            stats.ok,
            stats.errors,
            stats.truncated,
            stats.max_alloc,
            stats.max_alloc_raw,
            stats.inputs_per_second()
        );
    }
}

/// Largest allocation of one `cdr::decode::<T>`, and its result.
fn decode_measured<T: RosMessage>(bytes: &[u8]) -> (Result<T, CdrError>, usize) {
    fuzz::largest_allocation(|| cdr::decode::<T>(bytes))
}

/// Overwrite the word at `at` with 0xFFFFFFFF and append `extra` zero bytes.
fn with_max_length(mut bytes: Vec<u8>, at: usize, extra: usize) -> Vec<u8> {
    bytes[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    bytes.resize(bytes.len() + extra, 0);
    bytes
}

/// "Tiny": the error value and its path, nothing sized by the declared length.
const TINY: usize = 256;

#[test]
fn max_length_string_is_refused_without_allocating() {
    fuzz::assert_allocator_installed();
    use composuite_msgs::std_msgs::msg::String as RosString;
    let bytes = cdr::encode(&RosString { data: "abc".into() }).unwrap();
    assert_eq!(&bytes[4..8], &4u32.to_le_bytes());
    for extra in [0, 1 << 20] {
        let bad = with_max_length(bytes.clone(), 4, extra);
        let (result, largest) = decode_measured::<RosString>(&bad);
        let err = result.unwrap_err();
        assert_eq!(
            err,
            CdrError::Truncated {
                type_name: "std_msgs/msg/String",
                field: "data".into(),
                shortfall: Shortfall::String { len: u32::MAX },
                needed: u64::from(u32::MAX),
                remaining: 4 + extra,
            }
        );
        assert_eq!(
            err.to_string(),
            format!(
                "malformed std_msgs/msg/String: string `data` declares 4294967295 bytes, but only {} bytes are left",
                4 + extra
            )
        );
        assert!(largest <= TINY, "{largest} bytes allocated");
    }

    // Nested in a sequence element, big-endian.
    use composuite_msgs::geometry_msgs::msg::TransformStamped;
    use composuite_msgs::tf2_msgs::msg::TFMessage;
    let tf = TFMessage {
        transforms: vec![TransformStamped::default(); 2],
    };
    let mut bytes = vec![0, 0, 0, 0];
    bytes.extend(cdr_encoding::to_vec::<_, byteorder::BigEndian>(&tf).unwrap());
    // Body: count (4); transforms[0]: stamp (8), frame_id (4 + 1, padded to 16),
    // child_frame_id's length at body offset 20.
    assert_eq!(&bytes[24..28], &1u32.to_be_bytes());
    bytes[24..28].copy_from_slice(&[0xFF; 4]);
    let (result, largest) = decode_measured::<TFMessage>(&bytes);
    match result.unwrap_err() {
        CdrError::Truncated {
            field, shortfall, ..
        } => {
            assert_eq!(field, "transforms[0].child_frame_id");
            assert_eq!(shortfall, Shortfall::String { len: u32::MAX });
        }
        other => panic!("{other}"),
    }
    assert!(largest <= TINY, "{largest} bytes allocated");
}

#[test]
fn max_length_sequence_is_refused_without_allocating() {
    fuzz::assert_allocator_installed();
    use composuite_msgs::sensor_msgs::msg::JointState;
    let js = JointState {
        name: vec!["joint_1".into()],
        position: vec![0.5],
        ..Default::default()
    };
    let bytes = cdr::encode(&js).unwrap();
    let name_count = 4 + 16;
    let position_count = name_count + 4 + 12;
    assert_eq!(
        &bytes[position_count..position_count + 4],
        &1u32.to_le_bytes()
    );

    // The name count, then 1 MiB of zeros: plain cdr-encoding decodes 262,144 empty names into
    // a 6 MiB Vec before it runs out of input; the length check refuses the count first.
    let extra = 1 << 20;
    let bad = with_max_length(bytes[..name_count + 4].to_vec(), name_count, extra);
    let (result, largest) = decode_measured::<JointState>(&bad);
    let err = result.unwrap_err();
    assert!(
        matches!(
            &err,
            CdrError::Truncated { field, shortfall: Shortfall::Sequence { len: u32::MAX, element_size: 4 }, remaining, .. }
                if field == "name" && *remaining == extra
        ),
        "{err:?}"
    );
    assert!(
        err.to_string()
            .contains("sequence `name` declares 4294967295 elements"),
        "{err}"
    );
    assert!(largest <= TINY, "{largest} bytes allocated");
    let (raw, largest_raw) = fuzz::largest_allocation(|| {
        cdr_encoding::from_bytes::<JointState, byteorder::LittleEndian>(&bad[4..]).map(|_| ())
    });
    assert!(raw.is_err());
    assert!(
        largest_raw >= 6 << 20,
        "plain cdr-encoding allocated only {largest_raw}"
    );

    // A sequence of f64: the 8 bytes per element and the alignment padding are counted.
    let bad = with_max_length(bytes.clone(), position_count, extra);
    let (result, largest) = decode_measured::<JointState>(&bad);
    match result.unwrap_err() {
        CdrError::Truncated {
            field,
            shortfall,
            needed,
            remaining,
            ..
        } => {
            assert_eq!(field, "position");
            assert_eq!(
                shortfall,
                Shortfall::Sequence {
                    len: u32::MAX,
                    element_size: 8
                }
            );
            assert_eq!(
                (needed, remaining),
                (u64::from(u32::MAX) * 8 + 4, 20 + extra)
            );
        }
        other => panic!("{other}"),
    }
    assert!(largest <= TINY, "{largest} bytes allocated");

    // A sequence of messages: each ScenePart needs at least 86 bytes.
    use composuite_msgs::msg::Scene;
    let bytes = cdr::encode(&Scene::default()).unwrap();
    let parts_count = bytes.len() - 4;
    assert_eq!(&bytes[parts_count..], &0u32.to_le_bytes());
    let bad = with_max_length(bytes, parts_count, 4096);
    let (result, largest) = decode_measured::<Scene>(&bad);
    let err = result.unwrap_err();
    assert!(
        err.to_string().contains(
            "sequence `parts` declares 4294967295 elements of at least 86 bytes each \
             (369367187370 bytes), but only 4096 bytes are left"
        ),
        "{err}"
    );
    assert!(largest <= TINY, "{largest} bytes allocated");
}

#[test]
fn lengths_that_fit_still_decode() {
    // The check counts each element's smallest encoding: the shortest valid encodings pass.
    use composuite_msgs::sensor_msgs::msg::JointState;
    let js = JointState {
        name: vec![String::new(); 1000],
        ..Default::default()
    };
    let bytes = cdr::encode(&js).unwrap();
    assert_eq!(cdr::decode::<JointState>(&bytes).unwrap(), js);
    // A writer that sends empty strings as a bare zero length (no NUL) is accepted, as before.
    let mut bare = bytes[..24].to_vec();
    bare.extend(std::iter::repeat_n(0u8, 4 * 1000 + 12));
    assert_eq!(cdr::decode::<JointState>(&bare).unwrap(), js);
}

#[test]
fn allocation_bound_covers_every_type() {
    // The figures behind `fuzz::allocation_bound` (see its doc): rho = in-memory size over
    // smallest encoding, for every element type a sequence or array can have.
    struct Sizes {
        rho: f64,
        largest: usize,
    }
    impl MessageVisitor for Sizes {
        fn visit<T: RosMessage>(&mut self) {
            let min = fuzz::min_message_size(T::DESCRIPTION);
            assert!(min >= 1, "{} encodes in 0 bytes", T::ROS_NAME);
            let size = std::mem::size_of::<T>();
            self.rho = self.rho.max(size as f64 / min as f64);
            self.largest = self.largest.max(size);
        }
    }
    let string = std::mem::size_of::<String>() as f64
        / fuzz::min_encoded_size(&ElementType::String { bound: None }) as f64;
    let sequence = std::mem::size_of::<Vec<u8>>() as f64 / 4.0;
    let mut sizes = Sizes {
        rho: string.max(sequence).max(1.0),
        largest: std::mem::size_of::<String>(),
    };
    composuite_msgs::visit_messages(&mut sizes);
    eprintln!(
        "rho = {:.2}, largest element {} bytes",
        sizes.rho, sizes.largest
    );
    assert!(2.0 * sizes.rho <= fuzz::BOUND_PER_INPUT_BYTE as f64 / 4.0);
    assert!(4 * sizes.largest + 1024 <= fuzz::BOUND_CONSTANT / 4);
}
