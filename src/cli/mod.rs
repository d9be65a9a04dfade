//! The command line's larger subcommands, one file each, and the run's signal handling;
//! `main.rs` holds the rest and dispatches.
//! Part of the binary, not the library: it parses arguments and calls `drapekit::…`.

pub mod bench;
pub mod signals;
