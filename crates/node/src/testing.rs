//! Guard for tests that open DDS participants: they must run in a private network namespace
//! so that no discovery traffic leaves the machine.

/// Network interfaces of this process's network namespace (`/proc/self/net/dev`).
fn interfaces() -> std::io::Result<Vec<String>> {
    let text = std::fs::read_to_string("/proc/self/net/dev")?;
    Ok(text.lines().skip(2).filter_map(|l| l.split(':').next()).map(|n| n.trim().to_string()).collect())
}

/// Panics unless this process's network namespace has no interface but the loopback, as in
/// `tests/isolated` and `tests/run`. The namespace itself is checked, not an environment
/// variable, so a test cannot be talked into opening DDS on the host network.
pub fn require_isolated_network() {
    let found = interfaces().unwrap_or_else(|e| panic!("cannot list network interfaces (/proc/self/net/dev: {e}); DDS tests need a private network namespace"));
    let others: Vec<&String> = found.iter().filter(|n| *n != "lo").collect();
    if !others.is_empty() {
        panic!(
            "DDS tests must run in a private network namespace, but this one has {others:?}: use tests/run or tests/isolated \
             (e.g. `tests/isolated cargo test -p metrocell-node`)"
        );
    }
}

/// A child process (a node under test) killed and reaped when the guard drops, so a failing
/// test leaves no node running in the namespace.
pub struct KillOnDrop(pub std::process::Child);

impl Drop for KillOnDrop {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_loopback_is_always_listed() {
        assert!(super::interfaces().unwrap().iter().any(|n| n == "lo"));
    }
}
