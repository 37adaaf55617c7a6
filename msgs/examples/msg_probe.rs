//! Command-line access to the generated message layer, for interop tests run by peers we did
//! not write (Python `rosbags`, real rclpy): they drive this tool and compare.
//!
//! ```text
//! msg_probe describe                  # JSON: every type's names, hash, definition, fields
//! msg_probe random SEED COUNT         # JSON lines: {type, value, cdr} per random instance
//! msg_probe roundtrip < requests      # per JSON line {type, cdr}: decode, re-encode, report
//! ```

#[path = "../tests/support/mod.rs"]
mod support;

use std::io::{BufRead, Write};

use composuite_msgs::{MessageVisitor, RosMessage, RosService, ServiceVisitor, cdr};
use rand::SeedableRng;
use serde_json::{Value, json};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args
        .iter()
        .map(String::as_str)
        .collect::<Vec<_>>()
        .as_slice()
    {
        ["describe"] => describe(),
        ["random", seed, count] => match (seed.parse(), count.parse()) {
            (Ok(seed), Ok(count)) => random(seed, count),
            _ => Err(format!(
                "random SEED COUNT: both must be non-negative integers, got {seed} {count}"
            )),
        },
        ["roundtrip"] => roundtrip(),
        _ => Err("usage: msg_probe describe | random SEED COUNT | roundtrip < lines".into()),
    };
    if let Err(message) = result {
        eprintln!("msg_probe: {message}");
        std::process::exit(2);
    }
}

fn describe() -> Result<(), String> {
    struct Messages(serde_json::Map<String, Value>);
    impl MessageVisitor for Messages {
        fn visit<T: RosMessage>(&mut self) {
            let fields: Vec<&str> = T::DESCRIPTION.fields.iter().map(|f| f.name).collect();
            self.0.insert(
                T::ROS_NAME.into(),
                json!({"dds_name": T::DDS_NAME, "type_hash": T::TYPE_HASH, "definition": T::DEFINITION, "fields": fields}),
            );
        }
    }
    struct Services(serde_json::Map<String, Value>);
    impl ServiceVisitor for Services {
        fn visit<S: RosService>(&mut self) {
            self.0.insert(
                S::ROS_NAME.into(),
                json!({"type_hash": S::TYPE_HASH, "request": S::Request::ROS_NAME, "response": S::Response::ROS_NAME}),
            );
        }
    }
    let mut messages = Messages(Default::default());
    composuite_msgs::visit_messages(&mut messages);
    let mut services = Services(Default::default());
    composuite_msgs::visit_services(&mut services);
    println!(
        "{}",
        json!({"messages": messages.0, "services": services.0})
    );
    Ok(())
}

fn random(seed: u64, count: usize) -> Result<(), String> {
    struct Random {
        rng: rand_chacha::ChaCha8Rng,
        count: usize,
        out: std::io::StdoutLock<'static>,
    }
    impl MessageVisitor for Random {
        fn visit<T: RosMessage>(&mut self) {
            for _ in 0..self.count {
                let msg: T = support::random_message(&mut self.rng, 3);
                let bytes = cdr::encode(&msg).expect("random instances respect bounds");
                let line = json!({"type": T::ROS_NAME, "value": serde_json::to_value(&msg).unwrap(), "cdr": support::hex(&bytes)});
                writeln!(self.out, "{line}").unwrap();
            }
        }
    }
    let mut visitor = Random {
        rng: rand_chacha::ChaCha8Rng::seed_from_u64(seed),
        count,
        out: std::io::stdout().lock(),
    };
    composuite_msgs::visit_messages(&mut visitor);
    Ok(())
}

fn roundtrip() -> Result<(), String> {
    struct One<'a> {
        name: &'a str,
        bytes: &'a [u8],
        answer: Option<Value>,
    }
    impl MessageVisitor for One<'_> {
        fn visit<T: RosMessage>(&mut self) {
            if T::ROS_NAME != self.name {
                return;
            }
            self.answer = Some(match cdr::decode::<T>(self.bytes) {
                Ok(msg) => {
                    let again = cdr::encode(&msg).expect("decoded messages respect bounds");
                    json!({"type": T::ROS_NAME, "ok": true, "value": serde_json::to_value(&msg).unwrap(), "cdr": support::hex(&again)})
                }
                Err(e) => json!({"type": T::ROS_NAME, "ok": false, "error": e.to_string()}),
            });
        }
    }
    let stdin = std::io::stdin();
    let mut out = std::io::stdout().lock();
    for line in stdin.lock().lines() {
        let line = line.map_err(|e| e.to_string())?;
        if line.trim().is_empty() {
            continue;
        }
        let request: Value =
            serde_json::from_str(&line).map_err(|e| format!("bad request line: {e}"))?;
        let name = request["type"].as_str().ok_or("request without \"type\"")?;
        let bytes = support::unhex(request["cdr"].as_str().ok_or("request without \"cdr\"")?)?;
        let mut one = One {
            name,
            bytes: &bytes,
            answer: None,
        };
        composuite_msgs::visit_messages(&mut one);
        let answer = one
            .answer
            .unwrap_or_else(|| json!({"type": name, "ok": false, "error": "unknown type"}));
        writeln!(out, "{answer}").map_err(|e| e.to_string())?;
    }
    Ok(())
}
