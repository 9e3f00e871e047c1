//! Strict reading of JSON objects with key paths in every error.
//!
//! serde's derive cannot name the full key path of a bad value (it reports
//! `unknown field` without saying where), so parameter files are read into a
//! `serde_json::Value` and walked by hand with these helpers.

use serde_json::{Map, Value};

use crate::ParamError;

/// Short rendering of a JSON value for messages.
fn describe(v: &Value) -> String {
    let s = v.to_string();
    if s.len() > 40 {
        format!(
            "{}…",
            &s[..s.char_indices().nth(37).map_or(s.len(), |(i, _)| i)]
        )
    } else {
        s
    }
}

/// Joins a parent path and a key.
pub(crate) fn join(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    }
}

/// A JSON object being read; remembers its path for messages.
pub(crate) struct Obj<'a> {
    path: String,
    map: &'a Map<String, Value>,
}

impl<'a> Obj<'a> {
    /// Views `v` as an object, or errors naming `path`.
    pub fn new(v: &'a Value, path: &str) -> Result<Self, ParamError> {
        match v {
            Value::Object(map) => Ok(Self {
                path: path.to_string(),
                map,
            }),
            other => Err(ParamError::WrongType {
                key: if path.is_empty() {
                    "(top level)".into()
                } else {
                    path.into()
                },
                expected: "a JSON object",
                found: describe(other),
            }),
        }
    }

    /// Path of a key of this object.
    pub fn key_path(&self, key: &str) -> String {
        join(&self.path, key)
    }

    /// Errors if the object has a key outside `allowed`.
    pub fn only(&self, allowed: &[&str]) -> Result<(), ParamError> {
        for k in self.map.keys() {
            if !allowed.contains(&k.as_str()) {
                return Err(ParamError::Unknown {
                    key: self.key_path(k),
                    allowed: allowed.join(", "),
                });
            }
        }
        Ok(())
    }

    /// The value of an optional key.
    pub fn opt(&self, key: &str) -> Option<&'a Value> {
        self.map.get(key)
    }

    /// The value of a required key.
    pub fn req(&self, key: &str, expected: &'static str) -> Result<&'a Value, ParamError> {
        self.map.get(key).ok_or_else(|| ParamError::Missing {
            key: self.key_path(key),
            expected,
        })
    }

    /// A required sub-object.
    pub fn obj(&self, key: &str) -> Result<Obj<'a>, ParamError> {
        Obj::new(self.req(key, "an object")?, &self.key_path(key))
    }

    /// A required finite number.
    pub fn num(&self, key: &str) -> Result<f64, ParamError> {
        number(self.req(key, "a finite number")?, &self.key_path(key))
    }

    /// A required array of exactly `N` finite numbers.
    pub fn nums<const N: usize>(&self, key: &str) -> Result<[f64; N], ParamError> {
        let path = self.key_path(key);
        let v = self.req(key, "an array of numbers")?;
        let arr = v.as_array().ok_or_else(|| ParamError::WrongType {
            key: path.clone(),
            expected: "an array of numbers",
            found: describe(v),
        })?;
        if arr.len() != N {
            return Err(ParamError::WrongType {
                key: path,
                expected: "an array with the documented number of entries",
                found: format!("{} entries", arr.len()),
            });
        }
        let mut out = [0.0; N];
        for (i, (o, x)) in out.iter_mut().zip(arr).enumerate() {
            *o = number(x, &format!("{path}[{i}]"))?;
        }
        Ok(out)
    }
}

/// A finite number at `path`.
pub(crate) fn number(v: &Value, path: &str) -> Result<f64, ParamError> {
    let x = v.as_f64().ok_or_else(|| ParamError::WrongType {
        key: path.into(),
        expected: "a number",
        found: describe(v),
    })?;
    finite(x, path)
}

/// Errors if `x` is NaN or infinite.
pub(crate) fn finite(x: f64, path: &str) -> Result<f64, ParamError> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(ParamError::NonFinite {
            key: path.into(),
            value: x,
        })
    }
}

/// Parses JSON text, mapping syntax errors to line and column.
pub(crate) fn parse(text: &str) -> Result<Value, ParamError> {
    serde_json::from_str(text).map_err(|e| ParamError::Syntax {
        line: e.line(),
        column: e.column(),
        message: e.to_string(),
    })
}
