//! The benchmark run of the CDR decoder fuzzer (`tests/support/fuzz.rs`; `tests/fuzz.rs` is the
//! short CI run of the same generator): every message type, service requests, responses and
//! events included, gets N mutated-valid and random inputs.
//!
//! ```text
//! cargo run --release -p composuite_msgs --example fuzz_cdr -- --inputs 1000000 [--seed S] [--type NAME_PART]
//! ```
//!
//! Prints per type: inputs, decoded, errors (of them `truncated`: a length or field the buffer
//! cannot hold), the largest single allocation of `cdr::decode` (`raw_alloc`: of plain
//! `cdr-encoding`, what `ros2-client` decodes with), and inputs/s (generation and both decoders).
//! Exits 1 with a reproducible input at the first panic, allocation over the bound or
//! disagreement between the two decoders.

#[path = "../tests/support/mod.rs"]
mod support;

use std::time::Instant;

use support::fuzz::{self, Config, TypeStats};

#[global_allocator]
static ALLOCATOR: fuzz::CountingAlloc = fuzz::CountingAlloc;

fn parse_args() -> Result<Config, String> {
    let mut config = Config {
        seed: 0x00c0_ffee,
        inputs_per_type: 1_000_000,
        samples: 64,
        only: None,
    };
    let mut args = std::env::args().skip(1);
    while let Some(flag) = args.next() {
        let mut value = || args.next().ok_or(format!("{flag} needs a value"));
        match flag.as_str() {
            "--inputs" => {
                config.inputs_per_type = value()?.parse().map_err(|e| format!("--inputs: {e}"))?
            }
            "--seed" => config.seed = value()?.parse().map_err(|e| format!("--seed: {e}"))?,
            "--samples" => {
                config.samples = value()?.parse().map_err(|e| format!("--samples: {e}"))?
            }
            "--type" => config.only = Some(value()?),
            "--help" | "-h" => {
                return Err("usage: fuzz_cdr [--inputs N (1000000)] [--seed S] [--samples K (64)] [--type NAME_PART]".into());
            }
            other => return Err(format!("unknown argument {other}; see --help")),
        }
    }
    Ok(config)
}

fn row(s: &TypeStats) {
    println!(
        "{:<42} {:>9} {:>9} {:>9} {:>10} {:>10} {:>10} {:>9.0}",
        s.type_name,
        s.inputs,
        s.ok,
        s.errors,
        s.truncated,
        s.max_alloc,
        s.max_alloc_raw,
        s.inputs_per_second()
    );
}

fn main() {
    let config = match parse_args() {
        Ok(config) => config,
        Err(message) => {
            eprintln!("fuzz_cdr: {message}");
            std::process::exit(2);
        }
    };
    fuzz::assert_allocator_installed();
    println!(
        "seed {}, {} inputs per type, {} valid samples per type; bound per input: {} x len + {} bytes",
        config.seed,
        config.inputs_per_type,
        config.samples,
        fuzz::BOUND_PER_INPUT_BYTE,
        fuzz::BOUND_CONSTANT
    );
    println!(
        "{:<42} {:>9} {:>9} {:>9} {:>10} {:>10} {:>10} {:>9}",
        "type", "inputs", "decoded", "errors", "truncated", "max_alloc", "raw_alloc", "inputs/s"
    );
    let start = Instant::now();
    let result = fuzz::fuzz_all(&config, &mut row);
    let elapsed = start.elapsed();
    match result {
        Ok(all) => {
            let total = |f: fn(&TypeStats) -> u64| all.iter().map(f).sum::<u64>();
            let worst = all.iter().max_by_key(|s| s.max_alloc);
            println!(
                "total: {} types, {} inputs ({} decoded, {} errors, {} of them Truncated), {:.1} s, {:.0} inputs/s; largest allocation {} bytes ({}, input of {} bytes), plain cdr-encoding {} bytes; no panic, every allocation within the bound, both decoders agree",
                all.len(),
                total(|s| s.inputs),
                total(|s| s.ok),
                total(|s| s.errors),
                total(|s| s.truncated),
                elapsed.as_secs_f64(),
                total(|s| s.inputs) as f64 / elapsed.as_secs_f64(),
                worst.map_or(0, |s| s.max_alloc),
                worst.map_or("-", |s| s.type_name),
                worst.map_or(0, |s| s.max_alloc_input_len),
                all.iter().map(|s| s.max_alloc_raw).max().unwrap_or(0),
            );
        }
        Err(failure) => {
            eprintln!("fuzz_cdr: FAILED (seed {}): {failure}", config.seed);
            std::process::exit(1);
        }
    }
}
