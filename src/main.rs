//! The `rayoflight` binary: a thin shell around the library. All argument
//! handling and error reporting lives in `cli`.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
