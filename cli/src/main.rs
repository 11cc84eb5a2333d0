fn main() -> std::process::ExitCode {
    meshpyr::cli::main()
}
