//! Saving and loading plan files: atomic writes, versioned reads.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::model::{Plan, SCHEMA_VERSION};

#[derive(Debug, thiserror::Error)]
pub enum PlanIoError {
    #[error("{path}: cannot read plan file: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: cannot write plan file: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}:{line}:{column}: not a valid plan file: {reason}")]
    Corrupt {
        path: PathBuf,
        line: usize,
        column: usize,
        reason: String,
    },
    #[error("{path}: plan schema version {found} was written by a newer thinplan (this one reads up to {supported})")]
    TooNew {
        path: PathBuf,
        found: u64,
        supported: u32,
    },
    #[error("{path}: plan file has no `schema_version` field")]
    NoVersion { path: PathBuf },
}

/// Serialises a plan to its canonical bytes (pretty JSON, fields in
/// declaration order, maps ordered): the same plan always gives the same bytes.
pub fn to_bytes(plan: &Plan) -> Vec<u8> {
    let mut out = serde_json::to_vec_pretty(plan).expect("plan serialises");
    out.push(b'\n');
    out
}

/// Writes the plan atomically: to a temporary file in the same directory,
/// flushed to disk, then renamed over the target. A crash mid-write leaves
/// the previous file intact.
pub fn save(plan: &Plan, path: &Path) -> Result<(), PlanIoError> {
    write_atomic(path, &to_bytes(plan))
}

/// Atomic write of arbitrary bytes (used for plans and other outputs).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), PlanIoError> {
    let err = |source| PlanIoError::Write {
        path: path.to_path_buf(),
        source,
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "plan".into());
    let tmp = dir.join(format!(".{name}.tmp{}", std::process::id()));
    let result = (|| {
        let mut f = fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        drop(f);
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result.map_err(err)
}

/// Reads a plan file of this or any older schema version.
pub fn load(path: &Path) -> Result<Plan, PlanIoError> {
    let bytes = fs::read(path).map_err(|source| PlanIoError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    from_bytes(&bytes, path)
}

/// Parses plan bytes; `path` is only used in error messages.
pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<Plan, PlanIoError> {
    let corrupt = |e: serde_json::Error| PlanIoError::Corrupt {
        path: path.to_path_buf(),
        line: e.line(),
        column: e.column(),
        reason: e.to_string(),
    };
    let mut value: Value = serde_json::from_slice(bytes).map_err(corrupt)?;
    let version = value
        .get("schema_version")
        .and_then(Value::as_u64)
        .ok_or_else(|| PlanIoError::NoVersion {
            path: path.to_path_buf(),
        })?;
    if version > SCHEMA_VERSION as u64 {
        return Err(PlanIoError::TooNew {
            path: path.to_path_buf(),
            found: version,
            supported: SCHEMA_VERSION,
        });
    }
    migrate(&mut value, version);
    // Re-serialise the migrated value so that errors point into the canonical
    // form when migration happened, and into the file itself when it did not.
    if version == SCHEMA_VERSION as u64 {
        serde_json::from_slice(bytes).map_err(corrupt)
    } else {
        serde_json::from_value(value).map_err(corrupt)
    }
}

/// Upgrades a plan value from `from` to [`SCHEMA_VERSION`], one version at a
/// time. Each step is a pure function of the JSON value; every version ever
/// released keeps a frozen fixture under `crates/plan/tests/fixtures/` that
/// must keep loading.
/// Version 2 gave machining features the adjacency of their hole edges
/// (`hole_adjacency`, one list per hole); a v1 plan's features had none
/// recorded, so each hole gets an empty list (unknown).
fn migrate_1_to_2(value: &mut Value) {
    let Some(features) = value
        .get_mut("machining_features")
        .and_then(Value::as_array_mut)
    else {
        return;
    };
    for f in features {
        let holes = f
            .pointer("/shape/region/holes")
            .and_then(Value::as_array)
            .map_or(0, Vec::len);
        if let Some(obj) = f.as_object_mut() {
            obj.entry("hole_adjacency")
                .or_insert_with(|| Value::Array(vec![Value::Array(Vec::new()); holes]));
        }
    }
}

/// Version 3 gave machining features their origin (`origin`: the rule
/// that made them and their step role) and `access_blocked`, and operations
/// their `schedule`, as typed fields; a v2 plan recorded them only in the
/// provenance, from which they are read here, once.
fn migrate_2_to_3(value: &mut Value) {
    let flag = |p: &Value, key: &str| p.pointer(&format!("/values/{key}")).and_then(Value::as_f64);
    if let Some(features) = value
        .get_mut("machining_features")
        .and_then(Value::as_array_mut)
    {
        for f in features {
            let p = f.get("provenance").cloned().unwrap_or(Value::Null);
            let rule = p.get("rule").and_then(Value::as_str).unwrap_or("");
            let mut origin = serde_json::Map::new();
            origin.insert("rule".into(), Value::from(rule));
            if let Some(large) = flag(&p, "large") {
                origin.insert("large".into(), Value::from(large > 0.5));
            }
            if let Some(obj) = f.as_object_mut() {
                obj.entry("origin").or_insert(Value::Object(origin));
                if flag(&p, "access_blocked") == Some(1.0) {
                    obj.entry("access_blocked").or_insert(Value::from(true));
                }
            }
        }
    }
    if let Some(ops) = value.get_mut("operations").and_then(Value::as_array_mut) {
        for o in ops {
            let p = o.get("provenance").cloned().unwrap_or(Value::Null);
            let rule = p.get("rule").and_then(Value::as_str).unwrap_or("");
            let at_end = |within: Option<f64>| {
                let mut m = serde_json::Map::new();
                if let Some(w) = within {
                    m.insert("covered_within_mm".into(), Value::from(w));
                }
                serde_json::json!({ "at_end": m })
            };
            let schedule = if flag(&p, "orphan_stretches").is_some() {
                Some(at_end(None))
            } else if flag(&p, "after_every_feature") == Some(1.0) {
                Some(at_end(flag(&p, "min_left_mm")))
            } else if rule.ends_with(".rest_pass") || flag(&p, "run_last") == Some(1.0) {
                Some(Value::from("after_feature"))
            } else {
                None
            };
            if let (Some(s), Some(obj)) = (schedule, o.as_object_mut()) {
                obj.entry("schedule").or_insert(s);
            }
        }
    }
}

pub fn migrate(value: &mut Value, from: u64) {
    let mut v = from;
    while v < SCHEMA_VERSION as u64 {
        match v {
            1 => migrate_1_to_2(value),
            2 => migrate_2_to_3(value),
            _ => {}
        }
        v += 1;
    }
    if let Some(obj) = value.as_object_mut() {
        obj.insert("schema_version".into(), Value::from(SCHEMA_VERSION));
    }
}
