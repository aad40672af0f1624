//! `socnav`: the command-line tool. `run` rolls out a batch and prints outcome rates, the paper's
//! metrics and throughput; `bench` measures env-steps/s per stage over batch sizes;
//! `check-config` validates a config and prints it resolved; `render` draws an episode; `heatmap`
//! draws the discomfort around people in one scene; `devices`
//! lists the GPU adapters; `sngnn` installs the SNGNN-v2 weights and shows where they are.

mod args;
mod bench;
mod check;
mod devices;
mod heatmap;
mod policy;
mod render;
mod run;
mod sngnn;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = args::Cli::parse();
    let result = match cli.command {
        args::Command::Run(a) => run::run(&a),
        args::Command::Bench(a) => bench::bench(&a),
        args::Command::CheckConfig(a) => check::check(&a),
        args::Command::Render(a) => render::render(&a),
        args::Command::Heatmap(a) => heatmap::heatmap(&a),
        args::Command::Devices => devices::devices(),
        // Its own exit statuses: CI tells a failed download from a broken install.
        args::Command::Sngnn(c) => return sngnn::sngnn(&c),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
