//! Typed access to an instance's attributes, with errors that name the instance, its type and
//! the attribute (`#31 = CIRCLE: attribute 3 (radius): expected a number, found a string`).

use crate::StepError;
use crate::file::{Instance, Part, Value};

/// The attributes of one part of an instance.
#[derive(Clone, Copy, Debug)]
pub struct Attrs<'i, 'a> {
    /// The instance's number (`#id`), for messages.
    pub id: u64,
    /// The part's entity type name, e.g. `CIRCLE`.
    pub name: &'a str,
    /// The attribute values in file order.
    pub params: &'i [Value<'a>],
}

/// How a value is named in messages.
pub fn describe(v: &Value) -> &'static str {
    match v {
        Value::Int(_) => "an integer",
        Value::Real(_) => "a real number",
        Value::Str(_) => "a string",
        Value::Enum(_) => "an enumeration",
        Value::Ref(_) => "a reference",
        Value::List(_) => "a list",
        Value::Typed(..) => "a typed value",
        Value::Omitted => "'$' (omitted)",
        Value::Derived => "'*' (derived)",
        Value::Binary => "a binary value",
    }
}

/// A number (integer, real, or a typed measure such as `LENGTH_MEASURE(2.)`).
pub fn number(v: &Value) -> Option<f64> {
    match v {
        Value::Real(x) => Some(*x),
        Value::Int(i) => Some(*i as f64),
        Value::Typed(_, inner) if inner.len() == 1 => number(&inner[0]),
        _ => None,
    }
}

impl<'i, 'a> Attrs<'i, 'a> {
    /// The attributes of a part of `inst`.
    pub fn of(inst: &Instance<'a>, part: &'i Part<'a>) -> Self {
        Self {
            id: inst.id,
            name: part.name,
            params: &part.params,
        }
    }

    /// An error about the instance as a whole.
    pub fn fail(&self, message: impl Into<String>) -> StepError {
        StepError::entity(self.id, self.name, message)
    }

    /// An error about attribute `i` (0-based; messages count from 1).
    pub fn bad(&self, i: usize, what: &str, message: impl std::fmt::Display) -> StepError {
        self.fail(format!("attribute {} ({what}): {message}", i + 1))
    }

    /// Checks the attribute count.
    pub fn expect_len(&self, n: usize) -> Result<(), StepError> {
        if self.params.len() == n {
            Ok(())
        } else {
            Err(self.fail(format!(
                "expected {n} attributes, found {}",
                self.params.len()
            )))
        }
    }

    /// Attribute `i` (0-based); `what` names it in the error when it is missing.
    pub fn get(&self, i: usize, what: &str) -> Result<&'i Value<'a>, StepError> {
        self.params
            .get(i)
            .ok_or_else(|| self.bad(i, what, "missing"))
    }

    fn expected(&self, i: usize, what: &str, want: &str, got: &Value) -> StepError {
        self.bad(i, what, format!("expected {want}, found {}", describe(got)))
    }

    /// A finite number.
    pub fn real(&self, i: usize, what: &str) -> Result<f64, StepError> {
        let v = self.get(i, what)?;
        number(v).ok_or_else(|| self.expected(i, what, "a number", v))
    }

    /// Attribute `i` as an integer.
    pub fn int(&self, i: usize, what: &str) -> Result<i64, StepError> {
        match self.get(i, what)? {
            Value::Int(k) => Ok(*k),
            v => Err(self.expected(i, what, "an integer", v)),
        }
    }

    /// `.T.` or `.F.`.
    pub fn boolean(&self, i: usize, what: &str) -> Result<bool, StepError> {
        match self.get(i, what)? {
            Value::Enum(e) if e.eq_ignore_ascii_case("T") => Ok(true),
            Value::Enum(e) if e.eq_ignore_ascii_case("F") => Ok(false),
            v => Err(self.expected(i, what, ".T. or .F.", v)),
        }
    }

    /// Attribute `i` as an enumeration's name, without the dots.
    pub fn enumeration(&self, i: usize, what: &str) -> Result<&'a str, StepError> {
        match self.get(i, what)? {
            Value::Enum(e) => Ok(e),
            v => Err(self.expected(i, what, "an enumeration", v)),
        }
    }

    /// Attribute `i` as a reference `#id`.
    pub fn reference(&self, i: usize, what: &str) -> Result<u64, StepError> {
        match self.get(i, what)? {
            Value::Ref(r) => Ok(*r),
            v => Err(self.expected(i, what, "a reference", v)),
        }
    }

    /// A reference, or `None` for `$`.
    pub fn opt_reference(&self, i: usize, what: &str) -> Result<Option<u64>, StepError> {
        match self.get(i, what)? {
            Value::Ref(r) => Ok(Some(*r)),
            Value::Omitted => Ok(None),
            v => Err(self.expected(i, what, "a reference or $", v)),
        }
    }

    /// Attribute `i` as a list.
    pub fn list(&self, i: usize, what: &str) -> Result<&'i [Value<'a>], StepError> {
        match self.get(i, what)? {
            Value::List(l) => Ok(l),
            v => Err(self.expected(i, what, "a list", v)),
        }
    }

    /// A list of references.
    pub fn refs(&self, i: usize, what: &str) -> Result<Vec<u64>, StepError> {
        self.list(i, what)?
            .iter()
            .enumerate()
            .map(|(k, v)| match v {
                Value::Ref(r) => Ok(*r),
                v => Err(self.bad(
                    i,
                    what,
                    format!(
                        "item {}: expected a reference, found {}",
                        k + 1,
                        describe(v)
                    ),
                )),
            })
            .collect()
    }

    /// A list of numbers.
    pub fn reals(&self, i: usize, what: &str) -> Result<Vec<f64>, StepError> {
        self.list(i, what)?
            .iter()
            .enumerate()
            .map(|(k, v)| {
                number(v).ok_or_else(|| {
                    self.bad(
                        i,
                        what,
                        format!("item {}: expected a number, found {}", k + 1, describe(v)),
                    )
                })
            })
            .collect()
    }

    /// A list of integers.
    pub fn ints(&self, i: usize, what: &str) -> Result<Vec<i64>, StepError> {
        self.list(i, what)?
            .iter()
            .enumerate()
            .map(|(k, v)| match v {
                Value::Int(n) => Ok(*n),
                v => Err(self.bad(
                    i,
                    what,
                    format!("item {}: expected an integer, found {}", k + 1, describe(v)),
                )),
            })
            .collect()
    }
}
