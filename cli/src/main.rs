fn main() -> std::process::ExitCode {
    meshpyr_cli::main()
}
