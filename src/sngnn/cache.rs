//! Where the SNGNN-v2 weights live, and installing them there from the socnavgym 0.1.1 wheel.
//!
//! The weight file is GPL-3.0 and socnav does not redistribute it: `socnav sngnn install`
//! downloads the wheel from the package index (with the user's pip) and [`install_from_wheel`]
//! copies the one file out of it into a per-user cache. Lookup order ([`weights_path`]):
//!
//! 1. `SOCNAV_SNGNN_WEIGHTS`, a file path;
//! 2. the config's `reward.sngnn_weights`;
//! 3. the cache: `$SOCNAV_CACHE_DIR`, else `$XDG_CACHE_HOME/socnav`, else `~/.cache/socnav`; the
//!    file is `sngnn/SOCNAV_V2.tch` below it.
//!
//! A relative path (in the variable or the config) is taken from the current directory, not
//! from the config file's: configs also come from built-in names, strings and Python dicts, which
//! have no directory, and one rule for all is easier to predict. `~` is not expanded.

use std::ffi::OsString;
use std::fmt;
use std::fs::File;
use std::io::{BufReader, Read, Write};
use std::path::{Path, PathBuf};

use zip::ZipArchive;

use super::Weights;
use super::weights::WHEEL_ENTRY;
use crate::SimError;

/// Environment variable naming the weight file; it overrides the config.
pub const WEIGHTS_ENV: &str = "SOCNAV_SNGNN_WEIGHTS";
/// Environment variable naming socnav's cache directory.
pub const CACHE_ENV: &str = "SOCNAV_CACHE_DIR";
/// The weight file below the cache directory.
pub const CACHE_FILE: &str = "sngnn/SOCNAV_V2.tch";

/// The largest file taken from the wheel (the real one has 17,160,383 bytes).
const MAX_WEIGHTS_BYTES: u64 = 1 << 26;

/// Which rule chose the weight file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WeightsSource {
    /// The `SOCNAV_SNGNN_WEIGHTS` environment variable.
    Env,
    /// The config's `reward.sngnn_weights`.
    Config,
    /// The default cache location.
    Cache,
}

impl fmt::Display for WeightsSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            WeightsSource::Env => "from SOCNAV_SNGNN_WEIGHTS",
            WeightsSource::Config => "from the config's reward.sngnn_weights",
            WeightsSource::Cache => {
                "the default cache ($SOCNAV_CACHE_DIR, $XDG_CACHE_HOME/socnav or ~/.cache/socnav)"
            }
        })
    }
}

/// A resolved weight file and the rule that chose it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WeightsPath {
    /// The file (it may not exist).
    pub path: PathBuf,
    /// Which rule chose it.
    pub source: WeightsSource,
}

/// The weight file to use, given the config's `reward.sngnn_weights` (see the module docs for
/// the order). Only resolves: the file may not exist.
pub fn weights_path(config_value: Option<&str>) -> WeightsPath {
    resolve(config_value, &|k| std::env::var_os(k), std::env::home_dir())
}

/// socnav's cache directory: `$SOCNAV_CACHE_DIR`, else `$XDG_CACHE_HOME/socnav`, else
/// `~/.cache/socnav` (`.cache/socnav` in the current directory when there is no home).
pub fn cache_dir() -> PathBuf {
    resolve_cache_dir(&|k| std::env::var_os(k), std::env::home_dir())
}

/// The weight file below the cache directory `cache`.
pub fn cached_weights(cache: &Path) -> PathBuf {
    cache.join(CACHE_FILE)
}

/// Resolve the weight file ([`weights_path`]) and load it; a missing file is an error that says
/// how to install it.
pub fn load_weights(config_value: Option<&str>) -> Result<Weights, SimError> {
    let WeightsPath { path, source } = weights_path(config_value);
    if !path.is_file() {
        return Err(SimError::Sngnn(format!(
            "no weight file at {} ({source}).\n{}",
            path.display(),
            install_hint()
        )));
    }
    Weights::load(&path)
}

/// How to install the weights, for error messages.
pub fn install_hint() -> String {
    format!(
        "Install them with `socnav sngnn install` (downloads the socnavgym 0.1.1 wheel with pip \
         and copies SOCNAV_V2.tch into {}), or set {WEIGHTS_ENV} (or `reward.sngnn_weights`) to \
         a copy of {WHEEL_ENTRY} from that wheel (`python3 -m pip download socnavgym==0.1.1 \
         --no-deps`, then unzip). The file is GPL-3.0; socnav does not redistribute it.",
        cached_weights(&cache_dir()).display()
    )
}

/// Copy the weight file out of the socnavgym 0.1.1 wheel at `wheel` to `dest`, atomically
/// (a temporary file in the same directory, checked with the loader, then renamed): `dest` is
/// either the old file or a complete, valid new one. Returns the loaded weights.
pub fn install_from_wheel(wheel: &Path, dest: &Path) -> Result<Weights, SimError> {
    let bytes = read_wheel_entry(wheel)?;
    let dir = dest.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).map_err(|e| SimError::io("cannot create", dir, &e))?;
    let mut tmp = dest.as_os_str().to_owned();
    tmp.push(format!(".partial-{}", std::process::id()));
    let tmp = PathBuf::from(tmp);
    let result = write_synced(&tmp, &bytes)
        .and_then(|()| Weights::load(&tmp))
        .and_then(|w| {
            std::fs::rename(&tmp, dest).map_err(|e| {
                SimError::io(&format!("cannot move {} to", tmp.display()), dest, &e)
            })?;
            Ok(w)
        });
    if result.is_err() {
        // Best effort: the error that matters is the one returned.
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// The bytes of the weight file inside the wheel.
fn read_wheel_entry(wheel: &Path) -> Result<Vec<u8>, SimError> {
    let what = wheel.display();
    let file = File::open(wheel).map_err(|e| SimError::io("cannot open wheel", wheel, &e))?;
    let mut zip = ZipArchive::new(BufReader::new(file))
        .map_err(|e| SimError::Sngnn(format!("{what}: not a wheel (zip) archive: {e}")))?;
    let entry = zip
        .by_name(WHEEL_ENTRY)
        .map_err(|e| SimError::Sngnn(format!("{what}: no {WHEEL_ENTRY}: {e}")))?;
    let mut bytes = Vec::new();
    entry
        .take(MAX_WEIGHTS_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| SimError::Sngnn(format!("{what}: reading {WHEEL_ENTRY}: {e}")))?;
    if bytes.len() as u64 > MAX_WEIGHTS_BYTES {
        return Err(SimError::Sngnn(format!(
            "{what}: {WHEEL_ENTRY} is larger than {MAX_WEIGHTS_BYTES} bytes"
        )));
    }
    Ok(bytes)
}

/// Write `bytes` to a new file at `path` and flush them to the disk, so that the rename that
/// follows never publishes a file whose contents are still in flight.
fn write_synced(path: &Path, bytes: &[u8]) -> Result<(), SimError> {
    let io = |e: std::io::Error| SimError::io("cannot write", path, &e);
    let mut file = File::create(path).map_err(io)?;
    file.write_all(bytes).map_err(io)?;
    file.sync_all().map_err(io)
}

/// [`weights_path`] over an environment lookup `env` and a home directory.
fn resolve(
    config_value: Option<&str>,
    env: &dyn Fn(&str) -> Option<OsString>,
    home: Option<PathBuf>,
) -> WeightsPath {
    if let Some(path) = non_empty(env(WEIGHTS_ENV)) {
        return WeightsPath {
            path: PathBuf::from(path),
            source: WeightsSource::Env,
        };
    }
    if let Some(path) = config_value.filter(|p| !p.is_empty()) {
        return WeightsPath {
            path: PathBuf::from(path),
            source: WeightsSource::Config,
        };
    }
    WeightsPath {
        path: cached_weights(&resolve_cache_dir(env, home)),
        source: WeightsSource::Cache,
    }
}

fn resolve_cache_dir(env: &dyn Fn(&str) -> Option<OsString>, home: Option<PathBuf>) -> PathBuf {
    if let Some(dir) = non_empty(env(CACHE_ENV)) {
        return PathBuf::from(dir);
    }
    // The XDG spec says to ignore a relative XDG_CACHE_HOME.
    let xdg = non_empty(env("XDG_CACHE_HOME")).map(PathBuf::from);
    if let Some(xdg) = xdg.filter(|x| x.is_absolute()) {
        return xdg.join("socnav");
    }
    home.unwrap_or_default().join(".cache").join("socnav")
}

/// An empty variable counts as unset (as in the XDG spec).
fn non_empty(value: Option<OsString>) -> Option<OsString> {
    value.filter(|v| !v.is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env_of(pairs: &'static [(&'static str, &'static str)]) -> impl Fn(&str) -> Option<OsString> {
        move |k| {
            pairs
                .iter()
                .find(|(n, _)| *n == k)
                .map(|(_, v)| OsString::from(v))
        }
    }

    fn home() -> Option<PathBuf> {
        Some(PathBuf::from("/home/u"))
    }

    #[test]
    fn env_beats_config_beats_cache() {
        let env = env_of(&[(WEIGHTS_ENV, "w.tch"), (CACHE_ENV, "/c")]);
        let r = resolve(Some("cfg.tch"), &env, home());
        assert_eq!(
            (r.path, r.source),
            (PathBuf::from("w.tch"), WeightsSource::Env)
        );
        let env = env_of(&[(WEIGHTS_ENV, ""), (CACHE_ENV, "/c")]);
        let r = resolve(Some("cfg.tch"), &env, home());
        assert_eq!(
            (r.path, r.source),
            (PathBuf::from("cfg.tch"), WeightsSource::Config)
        );
        let r = resolve(None, &env, home());
        let expected = PathBuf::from("/c/sngnn/SOCNAV_V2.tch");
        assert_eq!((r.path, r.source), (expected, WeightsSource::Cache));
    }

    #[test]
    fn cache_dir_order() {
        let env = env_of(&[(CACHE_ENV, "/c"), ("XDG_CACHE_HOME", "/x")]);
        assert_eq!(resolve_cache_dir(&env, home()), PathBuf::from("/c"));
        let env = env_of(&[("XDG_CACHE_HOME", "/x")]);
        assert_eq!(resolve_cache_dir(&env, home()), PathBuf::from("/x/socnav"));
        // Relative or empty XDG_CACHE_HOME is ignored.
        for xdg in [
            &[("XDG_CACHE_HOME", "rel")][..],
            &[("XDG_CACHE_HOME", "")][..],
        ] {
            let env = env_of(xdg);
            let dir = resolve_cache_dir(&env, home());
            assert_eq!(dir, PathBuf::from("/home/u/.cache/socnav"));
        }
    }
}
