//! Torsional friction against the reference: each object resting on bin 1's floor, turned by a
//! torque about the vertical for 1 s (`tests/reference/data/spin.json`, recorded from the
//! reference with MuJoCo's `xfrc_applied`), and the same rig on the port: the yaw reached after
//! the 1 s, ours against the reference's, per object and torque.
//!
//! `cargo run --release -p composuite_core --example reference_spin`

#[path = "../tests/reference/mod.rs"]
mod reference;

fn main() {
    println!(
        "| task | torque (N·m) | yaw after 1 s, reference | ours | z at the end, reference | ours |"
    );
    println!("|---|---|---|---|---|---|");
    for spin in reference::spins() {
        let (ours, z_end) = spin.ours();
        println!(
            "| {} | {} | {:+.4} | {:+.4} | {:.3} | {:.3} |",
            spin.task,
            spin.torque,
            reference::Spin::turned(&spin.yaw, spin.torque_steps),
            reference::Spin::turned(&ours, spin.torque_steps),
            spin.z_end,
            z_end
        );
    }
}
