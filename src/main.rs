//! STUB CLI.
fn main() {}
