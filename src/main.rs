fn main() -> std::process::ExitCode {
    latticebuild::cli::main()
}
