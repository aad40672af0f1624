//! Loud skips. A test that cannot run here (no GPU adapter, no SNGNN-v2 weights, no reference
//! data) says so through [`skip`]: a `SKIPPED` line on stderr naming the test and the reason, and,
//! when `SOCNAV_SKIP_LOG` names a file, the same line appended to it, so that `scripts/test-all`
//! can count what did not run (libtest captures a passing test's output). [`required`] turns a
//! skip into a failure where the environment says the resource must be there (`REQUIRE_GPU=1`,
//! `REQUIRE_SNGNN=1`, as CI sets them).

use std::io::Write;

/// Whether the environment variable `var` is `1`: the resource must be there and a skip fails.
pub fn required(var: &str) -> bool {
    std::env::var(var).is_ok_and(|v| v == "1")
}

/// Record that the current test skips for `why`; panics instead when `require` (an environment
/// variable such as `REQUIRE_GPU`) is set to `1`.
pub fn skip(require: Option<&str>, why: &str) {
    if let Some(var) = require.filter(|v| required(v)) {
        panic!("{var}=1 but {why}");
    }
    let thread = std::thread::current();
    let test = thread.name().unwrap_or("a test");
    let line = format!("SKIPPED {test}: {why}");
    eprintln!("{line}");
    if let Some(path) = std::env::var_os("SOCNAV_SKIP_LOG").filter(|p| !p.is_empty()) {
        // One short write per line in append mode: lines of tests on other threads and processes
        // do not interleave.
        let appended = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&path)
            .and_then(|mut f| f.write_all(format!("{}\n", line.replace('\n', " ")).as_bytes()));
        if let Err(e) = appended {
            panic!("cannot append to SOCNAV_SKIP_LOG {path:?}: {e}");
        }
    }
}
