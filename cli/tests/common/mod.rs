//! Helpers of the command line's tests: the library's test helpers (`tests/common` at the
//! repository root) and running the `meshpyr` binary.
#![allow(dead_code, unused_imports)]

#[path = "../../../tests/common/mod.rs"]
mod library;
pub use library::*;

/// Runs the `meshpyr` binary with `args`.
pub fn meshpyr(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_meshpyr"))
        .args(args)
        .output()
        .expect("the meshpyr binary runs")
}

/// A path as the `&str` argument [`meshpyr`] takes.
pub fn path(p: &std::path::Path) -> &str {
    p.to_str().expect("a UTF-8 path")
}

/// Asserts that a run succeeded, showing its stderr otherwise.
pub fn ok(o: &std::process::Output) {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// The one-line error of a failed run (asserting it failed, and without a panic).
pub fn error_line(o: &std::process::Output) -> String {
    assert!(!o.status.success(), "expected a failure");
    let err = String::from_utf8_lossy(&o.stderr).trim().to_string();
    assert!(!err.contains("panicked"), "{err}");
    err
}

/// A test data file as the `String` argument a command line takes.
pub fn data_arg(name: &str) -> String {
    data(name).display().to_string()
}
