//! Loading a [`Config`]: from TOML text, a file, a shipped config's name, a SocNavGym 0.1.1
//! YAML file, or another config with overrides; every problem reported at once (unknown keys,
//! values that do not deserialise, longer ranges, and the value checks of [`super::validate`]),
//! and back to TOML.

use std::path::Path;

use super::validate::validate;
use super::{Config, socnavgym};
use crate::error::{ConfigProblem, SimError};

/// The largest config file read (bytes).
const MAX_CONFIG_BYTES: u64 = 1 << 20;

/// The shipped configs, built into the library so that their names work wherever it runs.
const SHIPPED: [(&str, &str); 9] = [
    ("exp1", include_str!("../../configs/exp1.toml")),
    ("exp2", include_str!("../../configs/exp2.toml")),
    ("exp3", include_str!("../../configs/exp3.toml")),
    ("exp1_sngnn", include_str!("../../configs/exp1_sngnn.toml")),
    ("exp2_sngnn", include_str!("../../configs/exp2_sngnn.toml")),
    ("exp3_sngnn", include_str!("../../configs/exp3_sngnn.toml")),
    (
        "lroom_mixed",
        include_str!("../../configs/lroom_mixed.toml"),
    ),
    (
        "corridor_mixed",
        include_str!("../../configs/corridor_mixed.toml"),
    ),
    ("stress", include_str!("../../configs/stress.toml")),
];

/// Every array of the config is a `[min, max]` range, and serde reads the first two items of a
/// longer one without a word: each array of `text` with more items, by its dotted key.
fn longer_ranges(text: &str) -> Vec<String> {
    fn walk(table: &toml::Table, prefix: &str, out: &mut Vec<String>) {
        for (key, value) in table {
            let name = format!("{prefix}{key}");
            match value {
                toml::Value::Table(t) => walk(t, &format!("{name}."), out),
                toml::Value::Array(items) if items.len() > 2 => out.push(format!(
                    "`{name}` must be [min, max], got an array of {} items",
                    items.len()
                )),
                _ => {}
            }
        }
    }
    let mut out = Vec::new();
    // The text parsed as a config already; a table that does not parse has no ranges to report.
    if let Ok(table) = text.parse::<toml::Table>() {
        walk(&table, "", &mut out);
    }
    out
}

impl Config {
    /// Parse a TOML document, then validate it; every problem is reported at once.
    pub fn from_toml_str(text: &str) -> Result<Self, SimError> {
        let mut text = text.to_owned();
        let mut problems = Vec::new();
        let config = loop {
            let mut unknown = Vec::new();
            let de =
                toml::Deserializer::parse(&text).map_err(|e| SimError::config([clipped(&e)]))?;
            match serde_ignored::deserialize(de, |path| unknown.push(path.to_string())) {
                Ok(config) => {
                    problems.extend(unknown.into_iter().map(|k| format!("unknown key `{k}`")));
                    break config;
                }
                // A value that does not deserialise (an unknown variant, a wrong type) is
                // reported and its line left out, so that the next parse finds the others.
                Err(e) => match without_bad_value(&text, &e) {
                    Some((rest, problem)) => {
                        problems.push(problem);
                        text = rest;
                    }
                    None => {
                        problems.push(clipped(&e));
                        return Err(SimError::config(problems));
                    }
                },
            }
        };
        problems.extend(longer_ranges(&text));
        problems.extend(validate(&config));
        if problems.is_empty() {
            Ok(config)
        } else {
            Err(SimError::config(problems))
        }
    }

    /// Read and validate a config file: socnav's TOML, or SocNavGym 0.1.1's YAML (a `.yaml` or
    /// `.yml` file, converted by [`Config::from_socnavgym_yaml`]).
    pub fn from_file(path: impl AsRef<Path>) -> Result<Self, SimError> {
        use std::io::Read;
        let path = path.as_ref();
        // A config is a few kilobytes: a larger file (`/dev/zero`, a dataset given by mistake) is
        // refused before it fills the memory.
        let mut bytes = Vec::new();
        std::fs::File::open(path)
            .and_then(|f| f.take(MAX_CONFIG_BYTES + 1).read_to_end(&mut bytes))
            .map_err(|e| SimError::io("cannot read config", path, &e))?;
        if bytes.len() as u64 > MAX_CONFIG_BYTES {
            return Err(SimError::config([format!(
                "the file is larger than {MAX_CONFIG_BYTES} bytes: not a config"
            )])
            .in_file(path));
        }
        let text = String::from_utf8(bytes).map_err(|e| {
            let e = std::io::Error::new(std::io::ErrorKind::InvalidData, e);
            SimError::io("cannot read config", path, &e)
        })?;
        if is_socnavgym_yaml(path) {
            Self::from_socnavgym_yaml(&text)
        } else {
            Self::from_toml_str(&text)
        }
        .map_err(|e| e.in_file(path))
    }

    /// Resolve a config name (`"exp1"` → `configs/exp1.toml`) or a path.
    pub fn from_name_or_path(name: &str) -> Result<Self, SimError> {
        let path = Path::new(name);
        if path.exists() {
            return Self::from_file(path);
        }
        match SHIPPED.iter().find(|(n, _)| *n == name) {
            Some((n, text)) => Self::from_toml_str(text)
                .map_err(|e| e.in_file(Path::new(&format!("configs/{n}.toml")))),
            None => {
                let names: Vec<&str> = SHIPPED.iter().map(|(n, _)| *n).collect();
                Err(SimError::Io {
                    path: Some(path.to_owned()),
                    kind: std::io::ErrorKind::NotFound,
                    message: format!(
                        "no config named `{name}`: neither a file nor one of the shipped configs ({})",
                        names.join(", ")
                    ),
                })
            }
        }
    }

    /// The names of the shipped configs (`configs/<name>.toml`), which are built into the library.
    pub fn shipped_names() -> impl Iterator<Item = &'static str> {
        SHIPPED.iter().map(|(n, _)| *n)
    }

    /// This config with `overrides` applied: a JSON object of sections and keys in the TOML
    /// layout (`{"counts": {"plants": [0, 2]}, "episode": {"length": 100}}`), merged key by
    /// key; `null` restores a key's default. The result is validated like a file, so unknown keys
    /// and bad values are all reported at once.
    pub fn with_overrides(&self, overrides: &serde_json::Value) -> Result<Self, SimError> {
        let mut table: toml::Table = toml::from_str(&self.to_toml_string())
            .map_err(|e| SimError::Internal(format!("a config does not parse back: {e}")))?;
        let serde_json::Value::Object(sections) = overrides else {
            return Err(SimError::config([format!(
                "overrides must be a table of sections, got {overrides}"
            )]));
        };
        let mut problems = Vec::new();
        merge_json(&mut table, sections, "", &mut problems);
        if !problems.is_empty() {
            return Err(SimError::config(problems));
        }
        let text = toml::to_string(&table)
            .map_err(|e| SimError::config([format!("the overridden config: {e}")]))?;
        Self::from_toml_str(&text)
    }

    /// Serialise to TOML (every key, resolved defaults included).
    #[expect(
        clippy::expect_used,
        reason = "every field is a number, string, bool or array of them, which TOML holds"
    )]
    pub fn to_toml_string(&self) -> String {
        toml::to_string_pretty(self).expect("a Config always serialises to TOML")
    }

    /// Convert the text of a SocNavGym 0.1.1 YAML config file into a validated socnav config.
    pub fn from_socnavgym_yaml(text: &str) -> Result<Self, SimError> {
        let (yaml, values) = socnavgym::parse_yaml(text)?;
        let values = values
            .into_iter()
            .map(ConfigProblem::new)
            .collect::<Vec<_>>();
        match (Self::from_socnavgym(&yaml), values.is_empty()) {
            (result, true) => result,
            // A value JSON cannot hold was left out as `null`: its own problem replaces the
            // converter's about the same key, and every other problem is kept.
            (Ok(_), false) => Err(SimError::Config(values)),
            (Err(SimError::Config(others)), false) => {
                let mut problems = values;
                let named =
                    |p: &ConfigProblem| problems.iter().any(|v| v.key.is_some() && v.key == p.key);
                let others: Vec<_> = others.into_iter().filter(|p| !named(p)).collect();
                problems.extend(others);
                Err(SimError::Config(problems))
            }
            (Err(other), false) => Err(other),
        }
    }

    /// Convert a SocNavGym 0.1.1 configuration (the YAML file parsed into a JSON value, as the
    /// golden episode headers carry it) into a validated socnav config.
    pub fn from_socnavgym(yaml: &serde_json::Value) -> Result<Self, SimError> {
        let config = socnavgym::convert(yaml)?;
        let problems = validate(&config);
        if problems.is_empty() {
            Ok(config)
        } else {
            Err(SimError::config(problems))
        }
    }
}

/// Whether `path` names a SocNavGym YAML config (`.yaml` or `.yml`, in any case).
pub fn is_socnavgym_yaml(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("yaml") || e.eq_ignore_ascii_case("yml"))
}

/// A TOML error's text, which quotes the offending line, cut to a readable length (a config of
/// one long line, machine-written, quoted whole ran to hundreds of kilobytes).
fn clipped(error: &toml::de::Error) -> String {
    clip(&error.to_string(), 2_000)
}

/// `text` cut after `max_chars` characters, saying how long it was.
fn clip(text: &str, max_chars: usize) -> String {
    match text.char_indices().nth(max_chars) {
        Some((cut, _)) => format!(
            "{} ... ({} characters in all)",
            &text[..cut],
            text.chars().count()
        ),
        None => text.to_owned(),
    }
}

/// `text` without the `key = value` line of the value that `error` points at, and the problem
/// naming its dotted key and the value; `None` when the error is not about a single-line value.
fn without_bad_value(text: &str, error: &toml::de::Error) -> Option<(String, String)> {
    let span = error.span()?;
    let start = text[..span.start].rfind('\n').map_or(0, |i| i + 1);
    let end = text[span.end..]
        .find('\n')
        .map_or(text.len(), |i| span.end + i);
    let line = &text[start..end];
    let key = line.split_once('=')?.0.trim();
    let bare = |k: &str| {
        !k.is_empty()
            && k.chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    };
    if !bare(key) || span.start < start + line.find('=')? {
        return None;
    }
    // The section: the last `[header]` line before the value (nested tables are dotted).
    let section = text[..start]
        .lines()
        .map(str::trim)
        .rfind(|l| l.starts_with('[') && !l.starts_with("[["))
        .and_then(|l| l.get(1..l.find(']')?))
        .map(str::trim);
    let path = section.map_or(key.to_owned(), |s| format!("{s}.{key}"));
    let problem = format!("`{path}` = {}: {}", clip(&text[span], 200), error.message());
    let mut rest = text[..start].to_owned();
    rest.push_str(&text[end..]);
    Some((rest, problem))
}

/// Merge the JSON object `from` into the TOML table `into`, key by key (tables recursively);
/// `null` removes a key so that its default applies. Values TOML cannot hold are reported in
/// `problems` with their dotted path.
fn merge_json(
    into: &mut toml::Table,
    from: &serde_json::Map<String, serde_json::Value>,
    prefix: &str,
    problems: &mut Vec<String>,
) {
    for (key, value) in from {
        let path = format!("{prefix}{key}");
        match value {
            serde_json::Value::Null => {
                into.remove(key);
            }
            serde_json::Value::Object(inner) => {
                let entry = into
                    .entry(key.clone())
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()));
                match entry {
                    toml::Value::Table(t) => merge_json(t, inner, &format!("{path}."), problems),
                    _ => problems.push(format!("`{path}` is a value, not a section")),
                }
            }
            other if matches!(into.get(key), Some(toml::Value::Table(_))) => {
                problems.push(format!("`{path}` is a section, not a value (got {other})"));
            }
            other => match toml::Value::try_from(other) {
                Ok(v) => {
                    into.insert(key.clone(), v);
                }
                Err(e) => problems.push(format!("`{path}` = {other}: {e}")),
            },
        }
    }
}
