//! `dexter`: run scenes, sweep parameters, analyze, write traces and plots (the command
//! line is `dexter_sim::cli`).

fn main() -> std::process::ExitCode {
    dexter_sim::cli::main()
}
