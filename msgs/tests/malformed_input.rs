//! Decoding never panics: truncated buffers, lengths pointing past the end, garbage, wrong
//! encapsulations and over-bound sequences are all errors (a property test over every type).

mod support;

use composuite_msgs::cdr::{self, CdrError};
use composuite_msgs::{MessageVisitor, RosMessage};
use rand::{Rng, RngCore, SeedableRng};

type Rng8 = rand_chacha::ChaCha8Rng;

#[test]
fn every_strict_prefix_is_an_error() {
    struct Prefixes(Rng8);
    impl MessageVisitor for Prefixes {
        fn visit<T: RosMessage>(&mut self) {
            for _ in 0..20 {
                let msg: T = support::random_message(&mut self.0, 3);
                let bytes = cdr::encode(&msg).unwrap();
                // Our encoder writes no trailing padding, so every byte is needed.
                for len in 0..bytes.len() {
                    let result = cdr::decode::<T>(&bytes[..len]);
                    assert!(
                        result.is_err(),
                        "{}: prefix of {len}/{} bytes decoded",
                        T::ROS_NAME,
                        bytes.len()
                    );
                }
            }
        }
    }
    composuite_msgs::visit_messages(&mut Prefixes(Rng8::seed_from_u64(1)));
}

#[test]
fn corrupted_words_and_garbage_never_panic() {
    struct Corrupt(Rng8, usize);
    impl MessageVisitor for Corrupt {
        fn visit<T: RosMessage>(&mut self) {
            for _ in 0..20 {
                let msg: T = support::random_message(&mut self.0, 3);
                let bytes = cdr::encode(&msg).unwrap();
                // Overwrite each aligned 4-byte word with huge or random lengths.
                for offset in (4..bytes.len().saturating_sub(3)).step_by(4) {
                    for word in [u32::MAX, 0x7fff_ffff, 0x0001_0000, self.0.next_u32()] {
                        let mut bad = bytes.clone();
                        bad[offset..offset + 4].copy_from_slice(&word.to_le_bytes());
                        let _ = cdr::decode::<T>(&bad);
                        self.1 += 1;
                    }
                }
            }
            for _ in 0..300 {
                let len = self.0.random_range(0..200);
                let mut garbage = vec![0u8; len];
                self.0.fill_bytes(&mut garbage);
                if len >= 2 && self.0.random_bool(0.7) {
                    garbage[..2].copy_from_slice(&cdr::CDR_LE);
                }
                let _ = cdr::decode::<T>(&garbage);
                self.1 += 1;
            }
        }
    }
    let mut visitor = Corrupt(Rng8::seed_from_u64(2), 0);
    composuite_msgs::visit_messages(&mut visitor);
    assert!(visitor.1 > 10_000, "only {} inputs tried", visitor.1);
}

#[test]
fn specific_errors_say_what_is_wrong() {
    use composuite_msgs::sensor_msgs::msg::JointState;
    assert_eq!(
        cdr::decode::<JointState>(&[0, 1, 0]),
        Err(CdrError::MissingHeader { len: 3 })
    );
    let err = cdr::decode::<JointState>(&[0, 7, 0, 0, 0, 0, 0, 0]).unwrap_err();
    assert_eq!(err, CdrError::UnsupportedEncapsulation { found: [0, 7] });
    assert!(
        err.to_string().contains("00 01 (CDR little-endian)"),
        "{err}"
    );

    let js = JointState {
        name: vec!["joint_1".into()],
        position: vec![0.5],
        ..Default::default()
    };
    let mut bytes = cdr::encode(&js).unwrap();
    // header.stamp (8) + frame_id length (4) + "\0" (1), padded to 4, then the name count.
    let count_at = 4 + 8 + 4 + 4;
    assert_eq!(&bytes[count_at..count_at + 4], &1u32.to_le_bytes());
    bytes[count_at..count_at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    let err = cdr::decode::<JointState>(&bytes).unwrap_err();
    // After the count: the name "joint_1" (4 + 8 bytes) and position, velocity, effort (4 + 4
    // + 8, 4, 4 bytes: the f64 is 8-aligned).
    assert_eq!(
        err,
        CdrError::Truncated {
            type_name: "sensor_msgs/msg/JointState",
            field: "name".into(),
            shortfall: cdr::Shortfall::Sequence {
                len: u32::MAX,
                element_size: 4
            },
            needed: u64::from(u32::MAX) * 4,
            remaining: 36,
        }
    );
    assert_eq!(
        err.to_string(),
        "malformed sensor_msgs/msg/JointState: sequence `name` declares 4294967295 elements of at \
         least 4 bytes each (17179869180 bytes), but only 36 bytes are left"
    );

    // Invalid UTF-8 in a string and a bool that is neither 0 nor 1.
    let s = composuite_msgs::std_msgs::msg::String { data: "ab".into() };
    let mut bytes = cdr::encode(&s).unwrap();
    bytes[8] = 0xff;
    assert!(matches!(
        cdr::decode::<composuite_msgs::std_msgs::msg::String>(&bytes),
        Err(CdrError::Malformed { .. })
    ));
    let b = cdr::encode(&composuite_msgs::std_msgs::msg::Bool { data: true }).unwrap();
    let mut bad = b.clone();
    bad[4] = 2;
    assert!(matches!(
        cdr::decode::<composuite_msgs::std_msgs::msg::Bool>(&bad),
        Err(CdrError::Malformed { .. })
    ));
}

#[test]
fn big_endian_input_decodes() {
    use byteorder::BigEndian;
    use composuite_msgs::sensor_msgs::msg::JointState;
    let js = JointState {
        name: vec!["a".into(), "b".into()],
        effort: vec![1.5, -2.0],
        ..Default::default()
    };
    let mut bytes = cdr::CDR_BE.to_vec();
    bytes.extend_from_slice(&[0, 0]);
    bytes.extend(cdr_encoding::to_vec::<_, BigEndian>(&js).unwrap());
    assert_eq!(cdr::decode::<JointState>(&bytes).unwrap(), js);
}

#[test]
fn bounded_sequences_are_enforced_both_ways() {
    use byteorder::LittleEndian;
    use composuite_msgs::srv::{ResetEvent, ResetRequest};
    let over = ResetEvent {
        request: vec![ResetRequest::default(), ResetRequest::default()],
        ..Default::default()
    };
    match cdr::encode(&over) {
        Err(CdrError::Bounds { error, .. }) => {
            assert_eq!(
                (error.path.as_str(), error.len, error.bound),
                ("request", 2, 1)
            );
        }
        other => panic!("expected a bounds error, got {other:?}"),
    }
    // A peer that ignores the bound: the decoder refuses the message.
    let mut bytes = cdr::CDR_LE.to_vec();
    bytes.extend_from_slice(&[0, 0]);
    bytes.extend(cdr_encoding::to_vec::<_, LittleEndian>(&over).unwrap());
    let err = cdr::decode::<ResetEvent>(&bytes).unwrap_err();
    assert!(
        err.to_string()
            .contains("field `request` has length 2, more than its bound 1"),
        "{err}"
    );
    let ok = ResetEvent {
        request: vec![ResetRequest {
            seed: 3,
            use_seed: true,
        }],
        ..Default::default()
    };
    assert_eq!(
        cdr::decode::<ResetEvent>(&cdr::encode(&ok).unwrap()).unwrap(),
        ok
    );
}
