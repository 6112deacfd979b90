//! The `wavepath` command. The command line (clap), progress bars (indicatif) and the
//! commands' glue live here, on the binary side; the library below knows nothing of them.

mod cli;

fn main() {
    std::process::exit(cli::main());
}
