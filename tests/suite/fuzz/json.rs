//! Mutations of JSON documents for the fuzz targets: any node of a document (a SocNavGym config
//! dict, a state document) replaced by a value just outside its bounds, a value of the wrong
//! type, a truncated or padded list, or removed.

use serde_json::{Value, json};

/// One step of the way to a node: an object key or an array index.
#[derive(Debug, Clone)]
pub enum Seg {
    Key(String),
    Index(usize),
}

/// The path of every node under `root` (the root itself excluded), depth first.
pub fn paths(root: &Value) -> Vec<Vec<Seg>> {
    let mut out = Vec::new();
    let mut here = Vec::new();
    walk(root, &mut here, &mut out);
    out
}

fn walk(v: &Value, here: &mut Vec<Seg>, out: &mut Vec<Vec<Seg>>) {
    let children: Vec<(Seg, &Value)> = match v {
        Value::Object(map) => map.iter().map(|(k, c)| (Seg::Key(k.clone()), c)).collect(),
        Value::Array(items) => items
            .iter()
            .enumerate()
            .map(|(i, c)| (Seg::Index(i), c))
            .collect(),
        _ => return,
    };
    for (seg, child) in children {
        here.push(seg);
        out.push(here.clone());
        walk(child, here, out);
        here.pop();
    }
}

/// The node at `path`, if an earlier mutation has not removed it.
pub fn at_mut<'a>(root: &'a mut Value, path: &[Seg]) -> Option<&'a mut Value> {
    path.iter().try_fold(root, |v, seg| match seg {
        Seg::Key(k) => v.get_mut(k.as_str()),
        Seg::Index(i) => v.get_mut(*i),
    })
}

/// Replace the node at `path` (if it is still there) by [`mutate`]`(node, kind, x)`.
pub fn mutate_at(root: &mut Value, path: &[Seg], kind: u8, x: f64) {
    if let Some(node) = at_mut(root, path) {
        *node = mutate(node, kind, x);
    }
}

/// Remove the node at `path` from its parent (an object loses the key, a list the element).
pub fn remove(root: &mut Value, path: &[Seg]) {
    let Some((last, parent)) = path.split_last() else {
        return;
    };
    match (at_mut(root, parent), last) {
        (Some(Value::Object(map)), Seg::Key(k)) => {
            map.remove(k);
        }
        (Some(Value::Array(items)), Seg::Index(i)) if *i < items.len() => {
            items.remove(*i);
        }
        _ => {}
    }
}

/// Strings that some enum-valued key of a config or document accepts, and some it does not.
const WORDS: [&str; 16] = [
    "square",
    "rectangle",
    "L",
    "no-walls",
    "random",
    "orca",
    "sfm",
    "static",
    "dynamic",
    "moving_group",
    "standing_group",
    "hl",
    "moving",
    "standing",
    "nan",
    "",
];

/// A replacement for `old` by mutation `kind` with the random number `x` in [0, 1): a number
/// scaled to or just past a bound, non-finite, or of the wrong type; a string another word; a
/// list truncated, emptied or padded; an object emptied.
pub fn mutate(old: &Value, kind: u8, x: f64) -> Value {
    let wrong_type = [
        json!(null),
        json!(true),
        json!("bogus"),
        json!({}),
        json!([]),
    ];
    if kind % 9 == 8 {
        return wrong_type[(x * wrong_type.len() as f64) as usize].clone();
    }
    match old {
        Value::Number(n) if n.is_f64() => {
            let f = n.as_f64().unwrap_or(0.0);
            match kind % 12 {
                0..=7 => {
                    let scale =
                        [0.0, 0.01, 0.5, 1.0 + 1e-6, 2.0, 10.0, 1e6, -1.0][usize::from(kind % 8)];
                    json!(f * scale + x * 1e-3)
                }
                8 => json!("nan"),
                9 => json!("inf"),
                10 => json!(1e38),
                _ => json!(-f),
            }
        }
        Value::Number(n) => {
            let i = n.as_i64().unwrap_or(0);
            match kind % 6 {
                0 => json!(0),
                1 => json!(-1),
                2 => json!(i.saturating_mul(3)),
                3 => json!((x * 50.0) as i64),
                4 => json!(u64::MAX),
                _ => json!(i + 1),
            }
        }
        Value::String(s) => {
            if kind.is_multiple_of(3) {
                json!(format!("{s}-bogus"))
            } else {
                json!(WORDS[(x * WORDS.len() as f64) as usize])
            }
        }
        Value::Bool(b) => json!(!b),
        Value::Array(items) => {
            let mut items = items.clone();
            match kind % 4 {
                0 => {
                    items.pop();
                }
                1 => items.clear(),
                2 => {
                    if let Some(first) = items.first().cloned() {
                        items.push(first);
                    }
                }
                _ => items.reverse(),
            }
            Value::Array(items)
        }
        Value::Object(_) => json!({}),
        Value::Null => json!(0),
    }
}
