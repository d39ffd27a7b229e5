//! Guard for tests that open DDS participants: they must run in a private network namespace
//! so that no discovery traffic leaves the machine.

/// Panics unless `METROCELL_ISOLATED=1` (set by `/work/shared/tools/isolated` and `tests/run`).
pub fn require_isolated_network() {
    if std::env::var("METROCELL_ISOLATED").as_deref() != Ok("1") {
        panic!(
            "DDS tests must run in a private network namespace: use tests/run or ../shared/tools/isolated \
             (e.g. `../shared/tools/isolated cargo test -p metrocell-node`)"
        );
    }
}
