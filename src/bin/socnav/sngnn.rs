//! `socnav sngnn install`: fetch the SNGNN-v2 weights as a user would, with pip, from the
//! socnavgym 0.1.1 wheel on the package index, and keep the one file socnav needs in its cache.
//! `socnav sngnn path`: where the weights are looked for and whether they are there.
//!
//! The weights are GPL-3.0: socnav never ships them, it only automates the download a user
//! could do by hand. Progress goes to stderr, results to stdout.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, ExitStatus};
use std::time::{SystemTime, UNIX_EPOCH};

use socnav::sngnn::{self, LAYERS, WEIGHTS_ENV, Weights, WeightsPath};
use socnav::{Config, SimError};

use crate::args::{InstallArgs, PathArgs, SngnnCommand};

/// Exit status when the wheel could not be downloaded (no Python, no pip, no network), so that
/// CI can skip what needs the weights instead of failing.
const DOWNLOAD_FAILED: u8 = 3;

/// Why a command failed.
enum Failure {
    /// The download failed; nothing on this machine is wrong with socnav.
    Download(String),
    /// Anything else.
    Other(String),
}

impl From<SimError> for Failure {
    fn from(e: SimError) -> Self {
        Failure::Other(e.to_string())
    }
}

/// Run `socnav sngnn <command>`.
pub fn sngnn(command: &SngnnCommand) -> ExitCode {
    let result = match command {
        SngnnCommand::Install(a) => install(a),
        SngnnCommand::Path(a) => path(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Download(m)) => {
            eprintln!("error: {m}");
            ExitCode::from(DOWNLOAD_FAILED)
        }
        Err(Failure::Other(m)) => {
            eprintln!("error: {m}");
            ExitCode::FAILURE
        }
    }
}

fn progress(line: &str) {
    eprintln!("socnav sngnn: {line}");
}

fn path(a: &PathArgs) -> Result<(), Failure> {
    let config_value = match &a.config {
        Some(c) => Config::from_name_or_path(c)?.reward.sngnn_weights,
        None => None,
    };
    let WeightsPath { path, source } = sngnn::weights_path(config_value.as_deref());
    println!("{}", path.display());
    println!("source: {source}");
    match std::fs::metadata(&path) {
        Ok(m) if m.is_file() => println!("exists: yes ({} bytes)", m.len()),
        _ => println!("exists: no (install with `socnav sngnn install`)"),
    }
    Ok(())
}

fn install(a: &InstallArgs) -> Result<(), Failure> {
    let cache = a.cache_dir.clone().unwrap_or_else(sngnn::cache_dir);
    let dest = sngnn::cached_weights(&cache);
    if !a.force && dest.is_file() {
        Weights::load(&dest).map_err(|e| {
            Failure::Other(format!(
                "{e}\nthe installed file is invalid: replace it with `socnav sngnn install --force`"
            ))
        })?;
        progress("already installed and valid (--force downloads it again)");
    } else {
        let tmp = TempDir::create()?;
        let wheel = download(&tmp.0)?;
        progress(&format!("extracting {}", sngnn::WHEEL_ENTRY));
        let weights = sngnn::install_from_wheel(&wheel, &dest)?;
        progress(&format!(
            "checked: {} tensors of {} layers, {} parameters",
            weights.tensors.len(),
            LAYERS.len(),
            weights.parameters()
        ));
    }
    println!("installed: {}", dest.display());
    println!(
        "note: SOCNAV_V2.tch is GPL-3.0 (SNGNN-v2, from the socnavgym 0.1.1 wheel); socnav \
         downloads it for you and does not redistribute it."
    );
    warn_if_not_found(&cache, &dest);
    Ok(())
}

/// Say so when the rules of `sngnn::weights_path` would not find the file just installed.
fn warn_if_not_found(cache: &Path, dest: &Path) {
    let resolved = sngnn::weights_path(None).path;
    if resolved == dest {
        return;
    }
    match std::env::var_os(WEIGHTS_ENV).filter(|v| !v.is_empty()) {
        Some(v) => progress(&format!(
            "{WEIGHTS_ENV}={} takes precedence over this file",
            PathBuf::from(v).display()
        )),
        None => progress(&format!(
            "socnav looks in {} by default: set SOCNAV_CACHE_DIR={} to use this one",
            resolved.display(),
            cache.display()
        )),
    }
}

/// Download the socnavgym 0.1.1 wheel into `dir` and return its path.
fn download(dir: &Path) -> Result<PathBuf, Failure> {
    let python = std::env::var_os("SOCNAV_PYTHON")
        .filter(|v| !v.is_empty())
        .unwrap_or_else(|| OsString::from("python3"));
    let shown = PathBuf::from(&python).display().to_string();
    progress(&format!(
        "downloading the socnavgym 0.1.1 wheel (about 16 MB) with `{shown} -m pip download`"
    ));
    let output = Command::new(&python)
        .args(["-m", "pip", "download", "socnavgym==0.1.1", "--no-deps"])
        .args(["--only-binary=:all:", "--disable-pip-version-check"])
        .args(["--progress-bar", "off", "-d"])
        .arg(dir)
        .output();
    let output = match output {
        Ok(o) => o,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(Failure::Download(format!(
                "`{shown}` not found: install Python 3 with pip, or set SOCNAV_PYTHON to an \
                 interpreter that has pip"
            )));
        }
        Err(e) => return Err(Failure::Download(format!("cannot run `{shown}`: {e}"))),
    };
    if !output.status.success() {
        let stderr = String::from_utf8_lossy(&output.stderr);
        return Err(Failure::Download(pip_failure(
            &shown,
            output.status,
            &stderr,
        )));
    }
    find_wheel(dir)
}

/// What a failed `pip download` means, with the end of pip's own message.
fn pip_failure(python: &str, status: ExitStatus, stderr: &str) -> String {
    if stderr.contains("No module named pip") {
        return format!(
            "`{python}` has no pip: install it (`{python} -m ensurepip --user`, or the system's \
             python3-pip package), or set SOCNAV_PYTHON to an interpreter that has it"
        );
    }
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    let tail = match lines.len() {
        0 => "(nothing on stderr)".to_owned(),
        n => lines[n.saturating_sub(12)..].join("\n  "),
    };
    format!(
        "pip could not download socnavgym 0.1.1 ({status}): is the package index reachable? \
         (pip's own settings apply: PIP_INDEX_URL, proxies). pip said:\n  {tail}"
    )
}

fn find_wheel(dir: &Path) -> Result<PathBuf, Failure> {
    let entries = std::fs::read_dir(dir)
        .map_err(|e| Failure::Other(format!("cannot list {}: {e}", dir.display())))?;
    entries
        .filter_map(Result::ok)
        .map(|e| e.path())
        .find(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("socnavgym-0.1.1-") && n.ends_with(".whl"))
        })
        .ok_or_else(|| {
            Failure::Other(format!(
                "pip succeeded but left no socnavgym-0.1.1 wheel in {}",
                dir.display()
            ))
        })
}

/// A fresh directory under the system's temporary directory, removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn create() -> Result<Self, Failure> {
        // The pid tells concurrent runs apart, the clock successive ones.
        let nanos = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.subsec_nanos());
        let name = format!("socnav-sngnn-{}-{nanos}", std::process::id());
        let dir = std::env::temp_dir().join(name);
        std::fs::create_dir(&dir)
            .map_err(|e| Failure::Other(format!("cannot create {}: {e}", dir.display())))?;
        Ok(TempDir(dir))
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        // Best effort: a leftover wheel in the temporary directory harms nothing.
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
