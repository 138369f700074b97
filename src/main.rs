//! The `gloffuse` binary: parse the command line, run, map errors to exit codes.

use clap::Parser;

fn main() {
    let cli = gloffuse::cli::Cli::parse();
    match gloffuse::app::run(cli) {
        Ok(code) => std::process::exit(code),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    }
}
