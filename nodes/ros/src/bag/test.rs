//! A bag written, read back, split, killed and reindexed — with the MCAP crate's own reader as
//! the judge of what is in the files.

use std::path::PathBuf;

use super::reader::{for_each_message, read_metadata, reindex};
use super::*;

fn scratch(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("composuite-bag-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn cdr(payload: &[u8]) -> Vec<u8> {
    let mut v = vec![0, 1, 0, 0];
    v.extend_from_slice(payload);
    v
}

/// A pseudo-random payload, so chunks do not compress to nothing.
fn payload(i: u64, len: usize) -> Vec<u8> {
    let mut x = i.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    (0..len)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x as u8
        })
        .collect()
}

const T0: u64 = 1_700_000_000_000_000_000;

fn write_bag(dir: &std::path::Path, options: BagOptions, messages: u64) -> BagMetadata {
    let mut bag = BagWriter::create(dir, options).unwrap();
    let obs = bag
        .add_topic(
            "/env/observation",
            "composuite_msgs/msg/Observation",
            vec![OfferedQos::discovered(true, false)],
            "",
        )
        .unwrap();
    let flag = bag
        .add_topic("/env/success", "std_msgs/msg/Bool", vec![], "")
        .unwrap();
    bag.add_topic("/never", "acme_msgs/msg/Unknown", vec![], "")
        .unwrap();
    for i in 0..messages {
        bag.write(
            obs,
            T0 + i * 1_000_000,
            T0 + i * 1_000_000 - 10,
            &cdr(&payload(i, 1500)),
        )
        .unwrap();
        bag.write(flag, T0 + i * 1_000_000 + 1, T0, &cdr(&[(i % 2) as u8]))
            .unwrap();
    }
    bag.close().unwrap()
}

#[test]
fn a_closed_bag_reads_back_exactly() {
    let dir = scratch("closed");
    let written = write_bag(&dir, BagOptions::default(), 200);
    assert_eq!(written.message_count, 400);
    assert_eq!(written.starting_time_ns, T0);
    assert_eq!(written.duration_ns, 199 * 1_000_000 + 1);
    assert_eq!(read_metadata(&dir).unwrap(), written);
    let counts: Vec<u64> = written.topics.iter().map(|t| t.message_count).collect();
    assert_eq!(counts, [200, 200, 0]);
    assert!(
        written.topics[0]
            .type_description_hash
            .starts_with("RIHS01_")
    );
    let mut seen = Vec::new();
    let truncated = for_each_message(&dir, |m| {
        seen.push((m.topic.to_string(), m.log_time, m.data.to_vec()));
        Ok(())
    })
    .unwrap();
    assert!(truncated.is_empty());
    assert_eq!(seen.len(), 400);
    assert_eq!(
        seen[0],
        ("/env/observation".into(), T0, cdr(&payload(0, 1500)))
    );
    assert_eq!(seen[399].2, cdr(&[1]));
    // The MCAP crate's summary agrees: statistics, every channel and schema, ros2 profile.
    let file = std::fs::read(dir.join(format!(
        "{}_0.mcap",
        dir.file_name().unwrap().to_string_lossy()
    )))
    .unwrap();
    let summary = mcap::read::Summary::read(&file).unwrap().unwrap();
    let stats = summary.stats.unwrap();
    assert_eq!(stats.message_count, 400);
    assert_eq!(summary.channels.len(), 3);
    let schema = &summary
        .channels
        .values()
        .find(|c| c.topic == "/env/observation")
        .unwrap()
        .schema;
    let schema = schema.as_ref().unwrap();
    assert_eq!(schema.encoding, "ros2msg");
    assert_eq!(schema.name, "composuite_msgs/msg/Observation");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_publisher_hash_that_is_not_ours_gets_no_schema() {
    let dir = scratch("hash");
    let mut bag = BagWriter::create(&dir, BagOptions::default()).unwrap();
    let ours = super::definitions::lookup("std_msgs/msg/Bool")
        .unwrap()
        .type_hash;
    bag.add_topic("/same", "std_msgs/msg/Bool", vec![], ours)
        .unwrap();
    bag.add_topic("/other", "std_msgs/msg/Bool", vec![], "RIHS01_00")
        .unwrap();
    let m = bag.close().unwrap();
    assert_eq!(m.topics[0].type_description_hash, ours);
    assert_eq!(m.topics[1].type_description_hash, "RIHS01_00");
    let file = std::fs::read(dir.join(&m.files[0].path)).unwrap();
    let summary = mcap::read::Summary::read(&file).unwrap().unwrap();
    let schema_of = |topic: &str| {
        let c = summary
            .channels
            .values()
            .find(|c| c.topic == topic)
            .unwrap();
        c.schema.as_ref().unwrap().encoding.clone()
    };
    assert_eq!(schema_of("/same"), "ros2msg");
    assert_eq!(schema_of("/other"), "");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_existing_directory_is_refused() {
    let dir = scratch("exists");
    std::fs::create_dir_all(&dir).unwrap();
    let e = BagWriter::create(&dir, BagOptions::default())
        .err()
        .unwrap();
    assert!(e.0.contains("already exists"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn files_split_by_size_and_duration() {
    let dir = scratch("split");
    let by_size = write_bag(
        &dir,
        BagOptions {
            max_file_size: 64 * 1024,
            chunk_size: 16 * 1024,
            ..BagOptions::default()
        },
        300,
    );
    assert!(by_size.files.len() >= 3, "{:?}", by_size.files);
    assert_eq!(
        by_size.files.iter().map(|f| f.message_count).sum::<u64>(),
        600
    );
    for (i, f) in by_size.files.iter().enumerate() {
        assert!(f.path.ends_with(&format!("_{i}.mcap")));
    }
    let mut n = 0;
    for_each_message(&dir, |_| {
        n += 1;
        Ok(())
    })
    .unwrap();
    assert_eq!(n, 600);
    let _ = std::fs::remove_dir_all(&dir);
    let by_time = write_bag(
        &dir,
        BagOptions {
            max_file_duration_ns: 50_000_000,
            ..BagOptions::default()
        },
        200,
    );
    assert_eq!(by_time.files.len(), 4, "{:?}", by_time.files);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_killed_recording_is_reindexed_to_its_last_complete_chunk() {
    let dir = scratch("killed");
    let options = BagOptions {
        chunk_size: 32 * 1024,
        ..BagOptions::default()
    };
    let full = write_bag(&dir, options, 400);
    let file = dir.join(&full.files[0].path);
    let bytes = std::fs::read(&file).unwrap();
    // Kill: no metadata.yaml, the file cut in the middle of its data section.
    std::fs::remove_file(dir.join("metadata.yaml")).unwrap();
    std::fs::write(&file, &bytes[..bytes.len() * 2 / 3]).unwrap();
    assert!(read_metadata(&dir).unwrap_err().0.contains("reindex"));
    let mut before = 0u64;
    let truncated = for_each_message(&dir, |_| {
        before += 1;
        Ok(())
    })
    .unwrap();
    assert_eq!(truncated.len(), 1, "the cut is reported");
    assert!(
        before > 100 && before < 800,
        "{before} messages before the cut"
    );

    let report = reindex(&dir).unwrap();
    assert_eq!(report.recovered.len(), 1);
    let m = read_metadata(&dir).unwrap();
    assert_eq!(m, report.metadata);
    assert_eq!(
        m.message_count, before,
        "every message of every complete chunk is kept"
    );
    assert_eq!(m.starting_time_ns, T0);
    assert_eq!(m.ros_distro, "jazzy");
    assert_eq!(m.topics.len(), 3, "topics without messages are kept");
    assert_eq!(
        m.topics[0].offered_qos_profiles,
        full.topics[0].offered_qos_profiles
    );
    assert_eq!(
        m.topics[0].type_description_hash,
        full.topics[0].type_description_hash
    );
    let repaired = std::fs::read(&file).unwrap();
    let summary = mcap::read::Summary::read(&repaired).unwrap().unwrap();
    assert_eq!(summary.stats.unwrap().message_count, before);
    // Reindexing a whole bag gives back what the writer wrote.
    let _ = std::fs::remove_dir_all(&dir);
    let written = write_bag(&dir, BagOptions::default(), 50);
    std::fs::remove_file(dir.join("metadata.yaml")).unwrap();
    let again = reindex(&dir).unwrap();
    assert!(again.recovered.is_empty());
    assert_eq!(again.metadata, written);
    let _ = std::fs::remove_dir_all(&dir);
}
