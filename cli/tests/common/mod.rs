//! Helpers of the command line's tests: the library's test helpers (`tests/common` at the
//! repository root) and running the `meshpyr` binary.
#![allow(dead_code, unused_imports)]

#[path = "../../../tests/common/mod.rs"]
mod library;
pub use library::*;

/// Runs the `meshpyr` binary with `args` (`&str`s or `String`s).
pub fn meshpyr<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_meshpyr"))
        .args(args)
        .output()
        .expect("the meshpyr binary runs")
}

/// A path as the `&str` argument [`meshpyr`] takes.
pub fn path(p: &std::path::Path) -> &str {
    p.to_str().expect("a UTF-8 path")
}

/// A run's standard error.
pub fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Asserts that a run succeeded, showing its stderr otherwise; returns the stderr (where the
/// commands say what they did).
pub fn ok(o: &std::process::Output) -> String {
    assert!(o.status.success(), "{}", stderr(o));
    stderr(o)
}

/// Asserts that a run failed with exactly one `error: ` line, the last one, holding `needle`
/// (status lines may come before it).
pub fn fails_with(o: &std::process::Output, needle: &str) {
    assert!(!o.status.success());
    let err = stderr(o);
    let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error: ")).collect();
    assert_eq!(errors.len(), 1, "{err}");
    assert!(errors[0].contains(needle), "{err}");
    assert!(
        err.trim_end().ends_with(errors[0]),
        "the error comes last: {err}"
    );
}

/// Asserts that a run failed with exit code 1 and nothing on stderr but a one-line error
/// holding every needle.
pub fn fails_alone_with(o: &std::process::Output, needles: &[&str]) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    for needle in needles {
        assert!(err.contains(needle), "{needle:?} not in {err}");
    }
}

/// A scratch file of the test `test` ([`scratch`]) as the `String` argument a command takes.
pub fn scratch_arg(test: &str, name: &str) -> String {
    scratch(test, name).display().to_string()
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
