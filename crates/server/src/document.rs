//! The design file as the workbench edits it: a TOML document whose comments, key order and
//! formatting survive every edit (`toml_edit`), seen by the page as the JSON design tree.
//!
//! An edit arrives as a whole new tree; [`DesignDocument::apply`] merges it into the document
//! key by key: a value equal to the one in the file keeps its text (so `63` stays `63`, a
//! multi-line point list keeps its lines), a changed value is rewritten in place with the key's
//! comments kept, a removed key goes, a new key is added at the end of its table. Arrays of
//! tables (`[[part.line]]`) are matched by their `name` where every element has a distinct one,
//! so deleting the second of four lines removes that block with its comment and leaves the others
//! as they were. A design read from JSON stays JSON (pretty-printed).

use serde_json::{Map, Value as Json};
use toml_edit::{Array, ArrayOfTables, DocumentMut, InlineTable, Item, Table, Value};

/// The design's text in the format of its file.
#[derive(Clone, Debug)]
pub enum DesignDocument {
    /// A TOML design, edited in place so its comments and layout survive.
    Toml(DocumentMut),
    /// A JSON design, written back pretty-printed.
    Json(Json),
}

/// A document that cannot be read or an edit that cannot be written as TOML.
#[derive(Debug, thiserror::Error)]
pub enum DocumentError {
    /// The text is not valid TOML or JSON.
    #[error("{file}:{line}:{col}: {message}")]
    Syntax {
        /// The design file.
        file: String,
        /// 1-based line (0 when the parser gives no position).
        line: usize,
        /// 1-based column (0 when the parser gives no position).
        col: usize,
        /// The parser's message.
        message: String,
    },
    /// The design tree has a shape the document cannot hold (a root that is not an object, a
    /// value TOML cannot write); the message says which.
    #[error("{0}")]
    Shape(String),
}

impl DesignDocument {
    /// Parses a design's text: TOML, or JSON when `json` is set; `file` names it in errors.
    pub fn parse(text: &str, json: bool, file: &str) -> Result<Self, DocumentError> {
        if json {
            return serde_json::from_str(text)
                .map(DesignDocument::Json)
                .map_err(|e| DocumentError::Syntax {
                    file: file.to_string(),
                    line: e.line(),
                    col: e.column(),
                    message: e.to_string(),
                });
        }
        text.parse::<DocumentMut>()
            .map(DesignDocument::Toml)
            .map_err(|e| {
                let (line, col) = e.span().map_or((0, 0), |s| line_col(text, s.start));
                DocumentError::Syntax {
                    file: file.to_string(),
                    line,
                    col,
                    message: e.message().to_string(),
                }
            })
    }

    /// The document's text, as it is written to its file.
    pub fn text(&self) -> String {
        match self {
            DesignDocument::Toml(d) => d.to_string(),
            DesignDocument::Json(j) => {
                let mut s = serde_json::to_string_pretty(j).unwrap_or_default();
                s.push('\n');
                s
            }
        }
    }

    /// Whether the document is JSON (else TOML).
    pub fn is_json(&self) -> bool {
        matches!(self, DesignDocument::Json(_))
    }

    /// The design as a JSON tree (TOML's tables as objects, arrays of tables as arrays).
    pub fn tree(&self) -> Json {
        match self {
            DesignDocument::Toml(d) => table_json(d.as_table()),
            DesignDocument::Json(j) => j.clone(),
        }
    }

    /// Merges `tree` into the document (see the module documentation). The tree's root must be
    /// an object.
    pub fn apply(&mut self, tree: &Json) -> Result<(), DocumentError> {
        let Json::Object(obj) = tree else {
            return Err(DocumentError::Shape(
                "the design must be an object ({\"units\": …, \"part\": […]})".into(),
            ));
        };
        match self {
            DesignDocument::Toml(d) => merge_table(d.as_table_mut(), obj, ""),
            DesignDocument::Json(j) => {
                *j = tree.clone();
                Ok(())
            }
        }
    }
}

fn line_col(src: &str, offset: usize) -> (usize, usize) {
    let before = &src[..offset.min(src.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

fn table_json(t: &Table) -> Json {
    let mut m = Map::new();
    for (k, item) in t.iter() {
        if let Some(v) = item_json(item) {
            m.insert(k.to_string(), v);
        }
    }
    Json::Object(m)
}

fn item_json(item: &Item) -> Option<Json> {
    match item {
        Item::None => None,
        Item::Value(v) => Some(value_json(v)),
        Item::Table(t) => Some(table_json(t)),
        Item::ArrayOfTables(a) => Some(Json::Array(a.iter().map(table_json).collect())),
    }
}

fn value_json(v: &Value) -> Json {
    match v {
        Value::String(s) => Json::String(s.value().clone()),
        Value::Integer(i) => Json::from(*i.value()),
        Value::Float(f) => {
            serde_json::Number::from_f64(*f.value()).map_or(Json::Null, Json::Number)
        }
        Value::Boolean(b) => Json::Bool(*b.value()),
        Value::Datetime(d) => Json::String(d.value().to_string()),
        Value::Array(a) => Json::Array(a.iter().map(value_json).collect()),
        Value::InlineTable(t) => {
            let mut m = Map::new();
            for (k, v) in t.iter() {
                m.insert(k.to_string(), value_json(v));
            }
            Json::Object(m)
        }
    }
}

/// A JSON value as a TOML value (objects become inline tables); `None` for `null`, which TOML
/// cannot hold (the key is left out).
fn json_value(j: &Json, at: &str) -> Result<Option<Value>, DocumentError> {
    Ok(Some(match j {
        Json::Null => return Ok(None),
        Json::Bool(b) => Value::from(*b),
        Json::Number(n) => match (n.as_i64(), n.as_f64()) {
            (Some(i), _) => Value::from(i),
            (None, Some(f)) if f.is_finite() => Value::from(f),
            _ => {
                return Err(DocumentError::Shape(format!(
                    "{at}: {n} is not a number TOML can hold"
                )));
            }
        },
        Json::String(s) => Value::from(s.as_str()),
        Json::Array(a) => {
            let mut arr = Array::new();
            for (k, x) in a.iter().enumerate() {
                if let Some(v) = json_value(x, &format!("{at}[{k}]"))? {
                    arr.push(v);
                }
            }
            Value::Array(arr)
        }
        Json::Object(o) => {
            let mut t = InlineTable::new();
            for (k, x) in o {
                if let Some(v) = json_value(x, &format!("{at}.{k}"))? {
                    t.insert(k, v);
                }
            }
            Value::InlineTable(t)
        }
    }))
}

/// A JSON value as a new TOML item: an object as a table, an array of objects as an array of
/// tables (as a designer writes `[[part.line]]`), anything else as a value.
fn json_item(j: &Json, at: &str) -> Result<Option<Item>, DocumentError> {
    match j {
        Json::Object(o) => {
            let mut t = Table::new();
            merge_table(&mut t, o, at)?;
            Ok(Some(Item::Table(t)))
        }
        Json::Array(a) if !a.is_empty() && a.iter().all(Json::is_object) => {
            let mut arr = ArrayOfTables::new();
            for (k, x) in a.iter().enumerate() {
                if let Some(Item::Table(t)) = json_item(x, &format!("{at}[{k}]"))? {
                    arr.push(t);
                }
            }
            Ok(Some(Item::ArrayOfTables(arr)))
        }
        other => Ok(json_value(other, at)?.map(Item::Value)),
    }
}

/// Merges `obj` into the table: equal values untouched, changed ones rewritten, missing keys
/// removed, new keys appended.
fn merge_table(t: &mut Table, obj: &Map<String, Json>, at: &str) -> Result<(), DocumentError> {
    let old_keys: Vec<String> = t.iter().map(|(k, _)| k.to_string()).collect();
    for k in old_keys {
        if !obj.contains_key(&k) || obj[&k].is_null() {
            t.remove(&k);
        }
    }
    for (k, new) in obj {
        let path = if at.is_empty() {
            k.clone()
        } else {
            format!("{at}.{k}")
        };
        let Some(old) = t.get_mut(k) else {
            if let Some(item) = json_item(new, &path)? {
                t.insert(k, item);
            }
            continue;
        };
        merge_item(old, new, &path)?;
    }
    Ok(())
}

/// Merges one value into an existing item, keeping its text where it is equal.
fn merge_item(old: &mut Item, new: &Json, at: &str) -> Result<(), DocumentError> {
    if item_json(old).as_ref() == Some(new) {
        return Ok(());
    }
    match (old, new) {
        (Item::Table(t), Json::Object(o)) => merge_table(t, o, at),
        (Item::Value(Value::InlineTable(t)), Json::Object(o)) => {
            merge_inline(t, o, at)?;
            Ok(())
        }
        (Item::ArrayOfTables(arr), Json::Array(a)) if a.iter().all(Json::is_object) => {
            merge_tables(arr, a, at)
        }
        (old, new) => {
            let decor = match old {
                Item::Value(v) => Some(v.decor().clone()),
                _ => None,
            };
            match json_item(new, at)? {
                Some(Item::Value(mut v)) => {
                    if let Some(d) = decor {
                        *v.decor_mut() = d;
                    }
                    *old = Item::Value(v);
                }
                Some(item) => *old = item,
                None => *old = Item::None,
            }
            Ok(())
        }
    }
}

fn merge_inline(
    t: &mut InlineTable,
    obj: &Map<String, Json>,
    at: &str,
) -> Result<(), DocumentError> {
    let old_keys: Vec<String> = t.iter().map(|(k, _)| k.to_string()).collect();
    for k in old_keys {
        if !obj.contains_key(&k) || obj[&k].is_null() {
            t.remove(&k);
        }
    }
    for (k, new) in obj {
        let path = format!("{at}.{k}");
        let keep = t.get(k).is_some_and(|v| &value_json(v) == new);
        if keep {
            continue;
        }
        match json_value(new, &path)? {
            Some(mut v) => {
                if let Some(old) = t.get(k) {
                    *v.decor_mut() = old.decor().clone();
                }
                t.insert(k, v);
            }
            None => {
                t.remove(k);
            }
        }
    }
    Ok(())
}

/// The `name` of every element, when all have one and no two are the same.
fn distinct_names<'a>(names: impl Iterator<Item = Option<&'a str>>) -> Option<Vec<&'a str>> {
    let names: Option<Vec<&str>> = names.collect();
    let names = names?;
    let mut sorted = names.clone();
    sorted.sort_unstable();
    sorted.dedup();
    (sorted.len() == names.len()).then_some(names)
}

/// Merges an array of tables: elements matched by name where every element (old and new) has a
/// distinct one, else by position.
fn merge_tables(arr: &mut ArrayOfTables, new: &[Json], at: &str) -> Result<(), DocumentError> {
    let old_names = distinct_names(arr.iter().map(|t| t.get("name").and_then(Item::as_str)));
    let new_names = distinct_names(new.iter().map(|j| j.get("name").and_then(Json::as_str)));
    let mut old_tables: Vec<Option<Table>> = arr.iter().cloned().map(Some).collect();
    let mut out = ArrayOfTables::new();
    for (k, j) in new.iter().enumerate() {
        let path = format!("{at}[{k}]");
        let Json::Object(o) = j else {
            return Err(DocumentError::Shape(format!("{path}: expected a table")));
        };
        let matched = match (&old_names, &new_names) {
            (Some(old), Some(newn)) => old.iter().position(|n| *n == newn[k]),
            _ => (k < old_tables.len()).then_some(k),
        };
        let mut t = matched
            .and_then(|m| old_tables.get_mut(m).and_then(Option::take))
            .unwrap_or_default();
        merge_table(&mut t, o, &path)?;
        out.push(t);
    }
    *arr = out;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    const SHOE_LIKE: &str = r#"# Generated by hand.
units = "mm"

[[part]]
name = "upper"
[part.surface]
type = "bezier"
degree = [1, 1]
points = [
  [0, 0, 0], [0, 100, 0],
  [100, 0, 0], [100, 100, 20],
]

[[part.line]]
# The first line.
name = "a"
points = [[50, 0, 0], [50, 100, 10]]

[[part.line]]
# The second line.
name = "b"
points = [[0, 50, 0], [100, 50, 10]]

[[part.piece]]
name = "left"
at = [25, 50, 0]   # inside the left region
"#;

    fn doc() -> DesignDocument {
        DesignDocument::parse(SHOE_LIKE, false, "d.toml").unwrap()
    }

    /// The tree read back unchanged leaves the text byte for byte as it was.
    #[test]
    fn an_unchanged_tree_keeps_every_byte() {
        let mut d = doc();
        let t = d.tree();
        d.apply(&t).unwrap();
        assert_eq!(d.text(), SHOE_LIKE);
    }

    /// Changing one point rewrites that value only; every comment and the other keys' text
    /// stay.
    #[test]
    fn a_changed_value_is_rewritten_in_place_with_its_comments() {
        let mut d = doc();
        let mut t = d.tree();
        t["part"][0]["piece"][0]["at"] = json!([30, 50, 0]);
        d.apply(&t).unwrap();
        let text = d.text();
        assert!(
            text.contains("at = [30, 50, 0]   # inside the left region\n"),
            "{text}"
        );
        assert_eq!(
            text.replace("at = [30, 50, 0]", "at = [25, 50, 0]"),
            SHOE_LIKE,
            "nothing else changed"
        );
    }

    /// Deleting the first of two named lines removes its block and comment; the other line
    /// keeps its own comment.
    #[test]
    fn a_removed_array_element_takes_its_comment_with_it() {
        let mut d = doc();
        let mut t = d.tree();
        t["part"][0]["line"].as_array_mut().unwrap().remove(0);
        d.apply(&t).unwrap();
        let text = d.text();
        assert!(!text.contains("The first line."), "{text}");
        assert!(!text.contains("name = \"a\""), "{text}");
        assert!(text.contains("# The second line.\nname = \"b\""), "{text}");
        assert!(text.contains("# Generated by hand."));
    }

    /// A new line is appended as a `[[part.line]]` block that the design loader reads back.
    #[test]
    fn a_new_line_becomes_an_array_of_tables_block() {
        let mut d = doc();
        let mut t = d.tree();
        t["part"][0]["line"]
            .as_array_mut()
            .unwrap()
            .push(json!({"name": "c", "points": [[10.5, 0, 0], [10.5, 100, 2]]}));
        d.apply(&t).unwrap();
        let text = d.text();
        assert!(
            text.contains("[[part.line]]\nname = \"c\"\npoints = [[10.5, 0, 0], [10.5, 100, 2]]"),
            "{text}"
        );
        let back = DesignDocument::parse(&text, false, "d.toml")
            .unwrap()
            .tree();
        assert_eq!(back, t);
    }

    /// A tree TOML cannot hold is refused with where it is.
    #[test]
    fn a_root_that_is_not_an_object_is_refused() {
        let mut d = doc();
        assert!(matches!(
            d.apply(&json!([1, 2])),
            Err(DocumentError::Shape(_))
        ));
    }

    /// A syntax error names the file, line and column.
    #[test]
    fn a_syntax_error_is_located() {
        let e = DesignDocument::parse("units = \"mm\"\n[[part]\n", false, "x.toml").unwrap_err();
        assert!(e.to_string().starts_with("x.toml:2:"), "{e}");
    }
}
