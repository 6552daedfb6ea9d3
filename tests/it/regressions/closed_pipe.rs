//! Issue 19 (found while checking the text tables): `lpc check --verbose | head -5` panicked in
//! `println!` once `head` closed the pipe, because Rust starts programs with SIGPIPE ignored.
//! The tool now ends quietly on a closed pipe, as Unix tools do.

use std::io::Read;
use std::process::Stdio;

use crate::common::lpc_command;

#[test]
fn a_closed_pipe_ends_the_tool_without_a_panic() {
    let mut child =
        lpc_command().args(["check", "--models", "reference", "--verbose"]).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    // Close the pipe at once: the tool spends a good fraction of a second running the scenes
    // before its first line, which then meets a closed pipe.
    drop(child.stdout.take());
    let mut stderr = String::new();
    child.stderr.take().unwrap().read_to_string(&mut stderr).unwrap();
    let status = child.wait().unwrap();
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_ne!(status.code(), Some(101), "a panic's exit code: {stderr}");
}
