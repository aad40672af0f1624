//! The RVO2 2.0.3 reference data (docs/spec.md orca-sfm 4): where it lives and a small reader
//! for its CSV files, shared by the CPU and GPU ORCA tests.

use std::collections::BTreeMap;
use std::io::Read;
use std::path::PathBuf;

/// The RVO2 reference data: `SOCNAV_REF_DIR`, or `tests/data/ref/orca_sfm` in the repository.
pub fn ref_dir() -> PathBuf {
    std::env::var_os("SOCNAV_REF_DIR")
        .filter(|d| !d.is_empty())
        .map_or_else(default_dir, PathBuf::from)
}

/// The repository's own copy of the reference data (`SOCNAV_REF_DIR` unset): the tests then
/// also assert the counts its README gives; other data sets of the format have their own.
pub fn is_own_copy() -> bool {
    ref_dir() == default_dir()
}

fn default_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/ref/orca_sfm")
}

/// The repository's harder RVO2 one-step cases, in the one-step format
/// (`tests/data/gen_orca_onestep_hard.py`).
pub fn hard_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/ref/orca_hard")
}

/// Whether the reference data is there; when it is not (`SOCNAV_REF_DIR` names a folder that
/// does not exist), says so on stdout for `test`, which then skips.
pub fn present(test: &str) -> bool {
    let dir = ref_dir();
    let here = dir.is_dir();
    if !here {
        super::skip::skip(
            None,
            &format!(
                "{test}: no RVO2/PySocialForce reference data at {} (SOCNAV_REF_DIR)",
                dir.display()
            ),
        );
    }
    here
}

/// A CSV file: header names and rows of string fields.
pub struct Table {
    /// Column names.
    pub header: Vec<String>,
    /// Rows of fields.
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// Read `name` from [`ref_dir`] (`.gz` files decompressed).
    pub fn load(name: &str) -> Self {
        Self::load_in(&ref_dir(), name)
    }

    /// Read `name` from `dir` (`.gz` files decompressed).
    pub fn load_in(dir: &std::path::Path, name: &str) -> Self {
        let path = dir.join(name);
        let mut text = String::new();
        let file = std::fs::File::open(&path)
            .unwrap_or_else(|e| panic!("cannot open {} ({e}); set SOCNAV_REF_DIR", path.display()));
        if name.ends_with(".gz") {
            flate2::read::GzDecoder::new(file).read_to_string(&mut text)
        } else {
            std::io::BufReader::new(file).read_to_string(&mut text)
        }
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
        let mut lines = text.lines().filter(|l| !l.is_empty());
        let header = lines
            .next()
            .expect("empty CSV")
            .split(',')
            .map(str::to_owned)
            .collect();
        let rows = lines
            .map(|l| l.split(',').map(str::to_owned).collect())
            .collect();
        Self { header, rows }
    }

    /// Index of column `name`.
    pub fn col(&self, name: &str) -> usize {
        self.header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name} in {:?}", self.header))
    }

    /// Column accessor: `t.f32s("px")(row)`.
    pub fn f32s(&self, name: &str) -> impl Fn(&[String]) -> f32 + use<> {
        let c = self.col(name);
        move |r: &[String]| {
            r[c].parse::<f32>()
                .unwrap_or_else(|e| panic!("{}: {e}", r[c]))
        }
    }

    /// Column accessor: `t.usizes("case")(row)`.
    pub fn usizes(&self, name: &str) -> impl Fn(&[String]) -> usize + use<> {
        let c = self.col(name);
        move |r: &[String]| {
            r[c].parse::<usize>()
                .unwrap_or_else(|e| panic!("{}: {e}", r[c]))
        }
    }

    /// Field `name` of `row` as an f32.
    pub fn f32(&self, row: &[String], name: &str) -> f32 {
        self.f32s(name)(row)
    }

    /// Field `name` of `row` as a usize.
    pub fn usize(&self, row: &[String], name: &str) -> usize {
        self.usizes(name)(row)
    }

    /// Rows grouped by the integer key in column `name` (sorted by key, rows in file order).
    pub fn group_by(&self, name: &str) -> BTreeMap<usize, Vec<&[String]>> {
        let key = self.usizes(name);
        let mut groups: BTreeMap<usize, Vec<&[String]>> = BTreeMap::new();
        for r in &self.rows {
            groups.entry(key(r)).or_default().push(r);
        }
        groups
    }
}
