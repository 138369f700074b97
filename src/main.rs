//! The `gloffuse` binary: the command-line layer (`cli`) over the `gloffuse` library.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
