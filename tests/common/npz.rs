//! Reading NumPy `.npz` archives (the golden SNGNN graph dumps): a zip of `.npy` files, each a
//! header (a Python dict literal with `descr`, `fortran_order`, `shape`) and the raw
//! little-endian values. Only what the golden files use: C order, `<f4`, `<i4`, `<i8`, `<f8`.

use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

/// One array: its shape and its values widened to f64 (every integer in the dumps fits).
#[derive(Debug, Clone)]
pub struct Array {
    pub shape: Vec<usize>,
    pub data: Vec<f64>,
}

impl Array {
    /// The values as f32 (for float32 arrays this is exact).
    pub fn f32s(&self) -> Vec<f32> {
        self.data.iter().map(|&x| x as f32).collect()
    }

    /// The values as indices.
    pub fn usizes(&self) -> Vec<usize> {
        self.data.iter().map(|&x| x as usize).collect()
    }
}

/// Every array of the archive at `path`, by name without the `.npy` suffix.
pub fn read_npz(path: &Path) -> BTreeMap<String, Array> {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut zip = zip::ZipArchive::new(file).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut arrays = BTreeMap::new();
    for i in 0..zip.len() {
        let mut entry = zip.by_index(i).unwrap();
        let name = entry.name().trim_end_matches(".npy").to_string();
        let mut bytes = Vec::new();
        entry.read_to_end(&mut bytes).unwrap();
        let array = parse_npy(&bytes).unwrap_or_else(|e| panic!("{}: {name}: {e}", path.display()));
        arrays.insert(name, array);
    }
    arrays
}

fn parse_npy(bytes: &[u8]) -> Result<Array, String> {
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err("not a .npy array".into());
    }
    let (header_len, start) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 => (
            u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize,
            12,
        ),
        v => return Err(format!(".npy version {v}")),
    };
    let header =
        std::str::from_utf8(&bytes[start..start + header_len]).map_err(|e| e.to_string())?;
    if !header.contains("'fortran_order': False") {
        return Err(format!("Fortran order: {header}"));
    }
    let descr = quoted_after(header, "'descr':").ok_or("no descr")?;
    let shape_text = header
        .split("'shape':")
        .nth(1)
        .and_then(|s| s.split(')').next())
        .ok_or("no shape")?;
    let shape: Vec<usize> = shape_text
        .trim_start_matches([' ', '('])
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().map_err(|e| format!("shape {s:?}: {e}")))
        .collect::<Result<_, _>>()?;
    let raw = &bytes[start + header_len..];
    let data: Vec<f64> = match descr {
        "<f4" => raw
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()) as f64)
            .collect(),
        "<f8" => raw
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect(),
        "<i4" => raw
            .chunks_exact(4)
            .map(|c| i32::from_le_bytes(c.try_into().unwrap()) as f64)
            .collect(),
        "<i8" => raw
            .chunks_exact(8)
            .map(|c| i64::from_le_bytes(c.try_into().unwrap()) as f64)
            .collect(),
        other => return Err(format!("dtype {other}")),
    };
    let n: usize = shape.iter().product();
    if data.len() != n {
        return Err(format!("{} values for shape {shape:?}", data.len()));
    }
    Ok(Array { shape, data })
}

fn quoted_after<'a>(header: &'a str, key: &str) -> Option<&'a str> {
    let rest = header.split(key).nth(1)?;
    let open = rest.find('\'')?;
    let close = rest[open + 1..].find('\'')?;
    Some(&rest[open + 1..open + 1 + close])
}
