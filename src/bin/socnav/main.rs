//! `socnav`: the command-line tool. `run` rolls out a batch and prints outcome rates, the paper's
//! metrics and throughput; `bench` measures env-steps/s per stage over batch sizes;
//! `check-config` validates a config and prints it resolved; `render` draws an episode; `heatmap`
//! draws the discomfort around people in one scene; `play` drives the robot by hand in a live
//! window; `soak` steps configs with adversarial actions for a long time, checking everything; `devices`
//! lists the GPU adapters; `sngnn` installs the SNGNN-v2 weights and shows where they are.

// A user's input never panics: every internal invariant that would is marked with
// `#[expect(clippy::..., reason = "...")]` saying why it holds (clippy.toml lets unit tests).
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod args;
mod bench;
mod check;
mod devices;
mod heatmap;
mod outcome;
mod play;
mod policy;
mod render;
mod run;
mod sngnn;
mod soak;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    quiet_wayland_probe();
    end_quietly_on_a_closed_pipe();
    fail_cleanly_when_output_cannot_be_written();
    let cli = args::Cli::parse();
    let result = match cli.command {
        args::Command::Run(a) => run::run(&a),
        args::Command::Bench(a) => bench::bench(&a),
        args::Command::CheckConfig(a) => check::check(&a),
        args::Command::Render(a) => render::render(&a),
        args::Command::Heatmap(a) => heatmap::heatmap(&a),
        args::Command::Play(a) => play::play(&a),
        args::Command::Soak(a) => soak::soak(&a),
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

/// Restore SIGPIPE's default action, as Unix tools have it: a reader that closes the pipe early
/// (`socnav devices | head -1`) ends this process quietly. Rust's runtime ignores SIGPIPE, which
/// makes `println!` panic on the broken pipe instead.
#[expect(
    unsafe_code,
    reason = "libc::signal is unsafe; sound here: called first thing in `main`, before any thread exists"
)]
fn end_quietly_on_a_closed_pipe() {
    #[cfg(unix)]
    // SAFETY: SIG_DFL is a valid disposition for SIGPIPE, and no other thread is running yet.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// A write to standard output or error that fails (a full disk: `socnav run > /dev/full`) makes
/// `println!` panic; the tool's output goes through it everywhere, so that panic is turned here
/// into what any other failure gives: a line saying why, and exit status 1. Every other panic
/// keeps Rust's report.
fn fail_cleanly_when_output_cannot_be_written() {
    let report = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let message = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or_default();
        if message.starts_with("failed printing to std") {
            use std::io::Write;
            // Standard error may be the stream that failed: nothing more can be said then.
            let _ = writeln!(std::io::stderr(), "error: {message}");
            std::process::exit(1);
        }
        report(info);
    }));
}

/// Mesa's Vulkan drivers probe Wayland while wgpu enumerates adapters, and libwayland prints
/// `error: XDG_RUNTIME_DIR is invalid or not set in the environment.` (twice per probe) on a
/// machine without a desktop session, where socnav mostly runs. socnav draws nothing on screen:
/// with the variable pointing at the temporary directory the probe finds no display and says
/// nothing. A variable the user set is left alone.
#[expect(
    unsafe_code,
    reason = "std::env::set_var is unsafe in edition 2024; sound here, see below"
)]
fn quiet_wayland_probe() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // SAFETY: called first thing in `main`, before any thread exists that could read the
        // environment concurrently.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
}
