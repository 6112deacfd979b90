fn main() {
    std::process::exit(wavepath::cli::main());
}
