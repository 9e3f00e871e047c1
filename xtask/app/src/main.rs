//! `aras`: the ARAS-Diamond toolkit's command-line tools (run through `cargo xtask`).

fn main() {}
