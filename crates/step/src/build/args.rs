//! Reading one entity's parameters: numbers, references, lists and
//! strings, with errors that name the entity and where it is in the file.

use crate::p21::{Exchange, Value};
use crate::{Place, StepErrorKind};

use super::R;

/// Arguments of one partial record, with error helpers naming the entity.
#[derive(Clone, Copy)]
pub(super) struct A<'x, 'a> {
    pub(super) ex: &'x Exchange<'a>,
    pub(super) idx: usize,
    pub(super) ty: &'x str,
    pub(super) vals: &'x [Value],
}

pub(super) fn place_of(ex: &Exchange<'_>, idx: usize) -> Place {
    match ex.entities.get(idx) {
        Some(e) => {
            let (line, column) = ex.line_col(e.offset as usize);
            Place {
                id: Some(e.id),
                line,
                column,
            }
        }
        None => Place {
            id: None,
            line: 0,
            column: 0,
        },
    }
}

pub(super) fn resolve_from(ex: &Exchange<'_>, from: usize, v: &Value) -> R<usize> {
    match v {
        Value::Ref(id) => ex.index_of(*id).ok_or_else(|| StepErrorKind::Dangling {
            place: place_of(ex, from),
            target: *id,
        }),
        _ => {
            let ty = ex
                .entities
                .get(from)
                .and_then(|e| ex.parts_of(e).first())
                .map(|p| ex.name(p.name))
                .unwrap_or("");
            Err(StepErrorKind::WrongParameter {
                place: place_of(ex, from),
                entity: ty.to_string(),
                reason: format!("expected a reference, found {}", describe(v)),
            })
        }
    }
}

fn describe(v: &Value) -> &'static str {
    match v {
        Value::Ref(_) => "a reference",
        Value::Int(_) => "an integer",
        Value::Real(_) => "a real",
        Value::Str(_) => "a string",
        Value::Enum(_) => "an enumeration",
        Value::Binary(_) => "a binary",
        Value::Null => "$",
        Value::Derived => "*",
        Value::List(_) => "a list",
        Value::Typed { .. } => "a typed parameter",
    }
}

impl<'x, 'a> A<'x, 'a> {
    pub(super) fn wrong(&self, reason: impl Into<String>) -> StepErrorKind {
        StepErrorKind::WrongParameter {
            place: place_of(self.ex, self.idx),
            entity: self.ty.to_string(),
            reason: reason.into(),
        }
    }

    fn get(&self, i: usize) -> R<&'x Value> {
        self.vals.get(i).ok_or_else(|| {
            self.wrong(format!(
                "expected at least {} parameters, found {}",
                i + 1,
                self.vals.len()
            ))
        })
    }

    pub(super) fn value_num(&self, v: &Value, what: &str) -> R<f64> {
        let x = match v {
            Value::Int(i) => *i as f64,
            Value::Real(r) => *r,
            Value::Typed { args, .. } => match self.ex.list(*args) {
                [inner] => return self.value_num(inner, what),
                _ => return Err(self.wrong(format!("{what}: expected a number"))),
            },
            other => {
                return Err(self.wrong(format!(
                    "{what}: expected a number, found {}",
                    describe(other)
                )))
            }
        };
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.wrong(format!("{what}: number out of range")))
        }
    }

    pub(super) fn num(&self, i: usize) -> R<f64> {
        self.value_num(self.get(i)?, &format!("parameter {}", i + 1))
    }

    pub(super) fn int(&self, i: usize) -> R<i64> {
        match self.get(i)? {
            Value::Int(v) => Ok(*v),
            Value::Real(r) if r.fract() == 0.0 && r.abs() < 1e15 => Ok(*r as i64),
            other => Err(self.wrong(format!(
                "parameter {}: expected an integer, found {}",
                i + 1,
                describe(other)
            ))),
        }
    }

    pub(super) fn logical(&self, i: usize) -> R<bool> {
        match self.get(i)? {
            Value::Enum(s) => match self.ex.raw(*s) {
                b"T" | b"TRUE" | b"U" | b"UNKNOWN" => Ok(true),
                b"F" | b"FALSE" => Ok(false),
                _ => Err(self.wrong(format!("parameter {}: expected .T. or .F.", i + 1))),
            },
            other => Err(self.wrong(format!(
                "parameter {}: expected .T. or .F., found {}",
                i + 1,
                describe(other)
            ))),
        }
    }

    pub(super) fn r(&self, i: usize) -> R<usize> {
        resolve_from(self.ex, self.idx, self.get(i)?)
    }

    pub(super) fn opt_r(&self, i: usize) -> R<Option<usize>> {
        match self.vals.get(i) {
            None | Some(Value::Null) | Some(Value::Derived) => Ok(None),
            Some(v) => resolve_from(self.ex, self.idx, v).map(Some),
        }
    }

    pub(super) fn list(&self, i: usize) -> R<&'x [Value]> {
        match self.get(i)? {
            Value::List(l) => Ok(self.ex.list(*l)),
            other => Err(self.wrong(format!(
                "parameter {}: expected a list, found {}",
                i + 1,
                describe(other)
            ))),
        }
    }

    pub(super) fn refs(&self, i: usize) -> R<Vec<usize>> {
        self.list(i)?
            .iter()
            .map(|v| resolve_from(self.ex, self.idx, v))
            .collect()
    }

    pub(super) fn string(&self, i: usize) -> String {
        match self.vals.get(i) {
            Some(Value::Str(s)) => self.ex.string(*s).into_owned(),
            _ => String::new(),
        }
    }
}
