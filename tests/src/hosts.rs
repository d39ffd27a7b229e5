//! Test hosts: several machines' networks on one machine, for tests of what crosses a network.
//!
//! Each host is a network namespace of its own (its own interfaces, addresses, routes and
//! multicast memberships), held open by an anchor process (`unshare -n sleep`), with one Ethernet
//! interface `eth0` (a veth pair) plugged into a bridge in the test's namespace — a switch between
//! the hosts. Host *i* has 10.88.0.*i*/24 and a 224.0.0.0/4 route on `eth0`, so DDS discovery
//! multicast goes from host to host through the bridge and nowhere else: the bridge and the hosts
//! live inside the test's own private namespace (tests/isolated), which has no way out.
//!
//! [`TestHosts::cut`] unplugs a host's cable at the switch (its bridge port goes down, the host's
//! `eth0` loses carrier); [`TestHosts::restore`] plugs it back in.
//!
//! Needs what tests/isolated needs (`unshare`, `nsenter` from util-linux, `ip` from iproute2)
//! and runs only inside such a namespace ([`require_isolated_network`]).

use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::require_isolated_network;

/// A set of hosts joined by one switch; removed (anchors killed, bridge deleted) when dropped.
pub struct TestHosts {
    bridge: String,
    hosts: Vec<Host>,
}

struct Host {
    name: String,
    anchor: Child,
    /// The host's cable at the switch: the bridge port in the test's namespace.
    port: String,
    address: String,
}

/// Runs `ip ARGS` (in the test's namespace, or with `netns` in a host's) and panics with its
/// error when it fails.
fn ip(netns: Option<u32>, args: &str) {
    let mut cmd = match netns {
        Some(pid) => {
            let mut c = Command::new("nsenter");
            c.arg(format!("--net=/proc/{pid}/ns/net")).arg("ip");
            c
        }
        None => Command::new("ip"),
    };
    let out = cmd
        .args(args.split_whitespace())
        .output()
        .unwrap_or_else(|e| panic!("cannot run ip {args}: {e} (needs iproute2 and util-linux)"));
    assert!(
        out.status.success(),
        "ip {args}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

impl TestHosts {
    /// Hosts named `names`, each with an address of 10.88.0.0/24 in the order given (from .1).
    pub fn create(names: &[&str]) -> TestHosts {
        require_isolated_network();
        // names unique to this test process: the tests of one binary share the namespace
        let tag = std::process::id() % 100_000;
        let bridge = format!("mcbr{tag}");
        ip(None, "link set lo up");
        ip(None, &format!("link add {bridge} type bridge"));
        // flood multicast to every port whatever IGMP says: a plain switch
        ip(
            None,
            &format!("link set {bridge} type bridge mcast_snooping 0"),
        );
        ip(None, &format!("link set {bridge} up"));
        let mut set = TestHosts {
            bridge,
            hosts: Vec::new(),
        };
        for (i, name) in names.iter().enumerate() {
            let anchor = Command::new("unshare")
                .args(["-n", "sleep", "infinity"])
                .stdin(Stdio::null())
                .spawn()
                .expect("unshare -n (util-linux)");
            let pid = anchor.id();
            // the anchor is in its own namespace once /proc says its net namespace differs
            let ours = std::fs::read_link("/proc/self/ns/net").unwrap();
            let deadline = Instant::now() + Duration::from_secs(5);
            while std::fs::read_link(format!("/proc/{pid}/ns/net"))
                .ok()
                .as_ref()
                == Some(&ours)
            {
                assert!(Instant::now() < deadline, "host {name}: no namespace");
                std::thread::sleep(Duration::from_millis(5));
            }
            let port = format!("mc{tag}h{i}");
            let address = format!("10.88.0.{}", i + 1);
            set.hosts.push(Host {
                name: name.to_string(),
                anchor,
                port: port.clone(),
                address: address.clone(),
            });
            ip(
                None,
                &format!("link add {port} type veth peer name eth0 netns /proc/{pid}/ns/net"),
            );
            ip(None, &format!("link set {port} master {} up", set.bridge));
            ip(Some(pid), "link set lo up");
            ip(Some(pid), &format!("addr add {address}/24 dev eth0"));
            ip(Some(pid), "link set eth0 up multicast on");
            ip(Some(pid), "route add 224.0.0.0/4 dev eth0");
        }
        set
    }

    fn host(&self, name: &str) -> &Host {
        self.hosts
            .iter()
            .find(|h| h.name == name)
            .unwrap_or_else(|| panic!("no test host {name}"))
    }

    /// The host's address (10.88.0.x).
    pub fn address(&self, name: &str) -> &str {
        &self.host(name).address
    }

    /// `program` to be run on host `name`, with the ROS environment of a networked machine:
    /// discovery over the subnet (the tests' localhost-only setting removed — the host's only
    /// network is the test switch).
    pub fn command(&self, name: &str, program: impl AsRef<std::ffi::OsStr>) -> Command {
        let mut c = Command::new("nsenter");
        c.arg(format!(
            "--net=/proc/{}/ns/net",
            self.host(name).anchor.id()
        ))
        .arg("--")
        .arg(program)
        .env_remove("ROS_LOCALHOST_ONLY")
        .env("ROS_AUTOMATIC_DISCOVERY_RANGE", "SUBNET")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
        c
    }

    /// Unplug host `name`'s cable at the switch.
    pub fn cut(&self, name: &str) {
        ip(None, &format!("link set {} down", self.host(name).port));
    }

    /// Plug it back in.
    pub fn restore(&self, name: &str) {
        ip(None, &format!("link set {} up", self.host(name).port));
    }
}

/// The pids of every process in the network namespace `ns` (a `/proc/PID/ns/net` link target).
fn processes_in(ns: &std::path::Path) -> Vec<i32> {
    let Ok(entries) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    entries
        .flatten()
        .filter_map(|e| e.file_name().to_string_lossy().parse::<i32>().ok())
        .filter(|pid| {
            std::fs::read_link(format!("/proc/{pid}/ns/net"))
                .ok()
                .as_deref()
                == Some(ns)
        })
        .collect()
}

impl Drop for TestHosts {
    fn drop(&mut self) {
        for h in &mut self.hosts {
            // whatever still runs on the host (a node its launch left, a failed test's
            // children) goes with it: a host left alive keeps its cable in the test's namespace,
            // which then has an interface besides `lo` and fails every later DDS test's guard
            if let Ok(ns) = std::fs::read_link(format!("/proc/{}/ns/net", h.anchor.id())) {
                for pid in processes_in(&ns) {
                    let _ = nix::sys::signal::kill(
                        nix::unistd::Pid::from_raw(pid),
                        nix::sys::signal::Signal::SIGKILL,
                    );
                }
            }
            let _ = h.anchor.kill();
            let _ = h.anchor.wait();
            // deleting our end deletes the pair now: a namespace whose last process is gone is
            // torn down by the kernel later, and until then its cable stays in ours (seen in the
            // full suite: the next test's guard found two of them)
            let _ = Command::new("ip").args(["link", "del", &h.port]).output();
        }
        let _ = Command::new("ip")
            .args(["link", "del", &self.bridge])
            .output();
    }
}
