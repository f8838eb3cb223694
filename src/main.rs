//! The `sweepmtf` command: parses arguments and dispatches to the library.

mod cli;
mod gui;

fn main() -> std::process::ExitCode {
    cli::main()
}
