//! Two node processes exchange every metrocell message type over DDS: this test publishes a
//! sample with every field non-default, the `roundtrip_peer` process (a separate node process)
//! receives it typed and publishes it back, and what returns must equal what was sent, field for
//! field (`system_tests::roundtrip`).

use std::process::Command;

use metrocell_node::MetrocellNode;
use system_tests::roundtrip::roundtrip_every_type;
use system_tests::{bin, require_isolated_network, ChildGuard};

#[test]
fn every_message_type_survives_a_round_trip_through_another_node_process() {
    require_isolated_network();
    let _peer = ChildGuard::spawn(&mut Command::new(bin("roundtrip_peer")));
    let mut node = MetrocellNode::builder("roundtrip_test")
        .diagnostics_period(None)
        .handle_signals(false)
        .build()
        .unwrap();
    let (failures, checked) = roundtrip_every_type(&mut node, 11);
    assert!(checked >= 31, "only {checked} types checked");
    assert!(
        failures.is_empty(),
        "{} of {checked} types failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
