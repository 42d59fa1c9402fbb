//! The table writer of `ssbvb bench`: a preset describes its rows once, as a [`Table`] of
//! named [`Column`]s whose cells are typed [`Value`]s, and the table writes them as CSV
//! (header and rows), as Markdown (a header, an alignment row and rows) and as JSON (an
//! array of objects, through serde). Each column says which of the three it appears in
//! and, for the text ones, how its cells are printed ([`Fmt`]: CSV may print `{}` where
//! Markdown prints `{:.2}`). A column's place is the same in all three; a cell only one
//! output needs (a Markdown `size` made of width and height) is a column of that output
//! alone. [`write_files`] writes a report's files atomically.

mod json;

use std::fmt::{Display, LowerExp};
use std::path::Path;

use anyhow::{Context, Result};
use serde::ser::{Error as _, SerializeMap, SerializeSeq};
use serde::{Serialize, Serializer};

pub(crate) use json::Json;

/// One cell.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Value {
    /// No value: JSON null, and the format's `missing` text in CSV and Markdown.
    Null,
    Bool(bool),
    U64(u64),
    I64(i64),
    /// Printed at its own width: `0.1f32` is `0.1` (it would be `0.10000000149011612` as
    /// an `f64`).
    F32(f32),
    F64(f64),
    Str(String),
    /// A whole serde value (JSON only).
    Json(Json),
    /// A serde struct whose fields become entries of the row's JSON object at the column's
    /// place, as `#[serde(flatten)]` writes them (JSON only).
    Flatten(Json),
}

macro_rules! value_from {
    ($($t:ty => $v:ident as $as:ty),* $(,)?) => {
        $(impl From<$t> for Value {
            fn from(v: $t) -> Self {
                Value::$v(v as $as)
            }
        })*
    };
}

value_from!(
    u32 => U64 as u64,
    u64 => U64 as u64,
    usize => U64 as u64,
    i32 => I64 as i64,
    i64 => I64 as i64,
    f32 => F32 as f32,
    f64 => F64 as f64,
);

impl From<bool> for Value {
    fn from(v: bool) -> Self {
        Value::Bool(v)
    }
}

impl From<&str> for Value {
    fn from(v: &str) -> Self {
        Value::Str(v.to_string())
    }
}

impl From<String> for Value {
    fn from(v: String) -> Self {
        Value::Str(v)
    }
}

impl From<Json> for Value {
    fn from(v: Json) -> Self {
        Value::Json(v)
    }
}

impl<T: Into<Value>> From<Option<T>> for Value {
    fn from(v: Option<T>) -> Self {
        v.map_or(Value::Null, Into::into)
    }
}

impl Value {
    /// `value` as serde writes it, as one JSON cell.
    pub(crate) fn json<T: Serialize + ?Sized>(value: &T) -> Value {
        Value::Json(Json::of(value))
    }

    /// The fields of `value` as entries of the row (see [`Value::Flatten`]).
    pub(crate) fn flatten<T: Serialize + ?Sized>(value: &T) -> Value {
        Value::Flatten(Json::of(value))
    }
}

impl Serialize for Value {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Value::Null => s.serialize_none(),
            Value::Bool(v) => s.serialize_bool(*v),
            Value::U64(v) => s.serialize_u64(*v),
            Value::I64(v) => s.serialize_i64(*v),
            Value::F32(v) => s.serialize_f32(*v),
            Value::F64(v) => s.serialize_f64(*v),
            Value::Str(v) => s.serialize_str(v),
            Value::Json(v) => v.serialize(s),
            Value::Flatten(_) => Err(S::Error::custom("a flattened cell outside its row")),
        }
    }
}

/// How a number is printed.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Style {
    /// `{}`
    Plain,
    /// `{:.N}`
    Fixed(usize),
    /// `{:.Ne}`
    Exp(usize),
}

/// How a column's cells are printed in CSV or Markdown: a number style, and the text of a
/// missing cell ([`Value::Null`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Fmt {
    style: Style,
    missing: &'static str,
}

impl Fmt {
    /// `{}`; missing cells empty.
    pub(crate) const PLAIN: Fmt = Fmt {
        style: Style::Plain,
        missing: "",
    };

    /// `{:.digits}`; missing cells empty.
    pub(crate) const fn fixed(digits: usize) -> Fmt {
        Fmt {
            style: Style::Fixed(digits),
            missing: "",
        }
    }

    /// `{:.digits e}`; missing cells empty.
    pub(crate) const fn exp(digits: usize) -> Fmt {
        Fmt {
            style: Style::Exp(digits),
            missing: "",
        }
    }

    /// This format with `missing` as the text of a missing cell.
    pub(crate) const fn or(self, missing: &'static str) -> Fmt {
        Fmt { missing, ..self }
    }

    fn number<T: Display + LowerExp>(self, v: T) -> String {
        match self.style {
            Style::Plain => format!("{v}"),
            Style::Fixed(n) => format!("{v:.n$}"),
            Style::Exp(n) => format!("{v:.n$e}"),
        }
    }

    /// The text of `v`.
    pub(crate) fn text(self, v: &Value) -> String {
        match v {
            Value::Null => self.missing.to_string(),
            Value::Bool(b) => b.to_string(),
            Value::U64(x) => self.number(*x),
            Value::I64(x) => self.number(*x),
            Value::F32(x) => self.number(*x),
            Value::F64(x) => self.number(*x),
            Value::Str(s) => s.clone(),
            Value::Json(j) | Value::Flatten(j) => serde_json::to_string(j).unwrap_or_default(),
        }
    }
}

/// A column's Markdown side.
struct Md {
    header: String,
    fmt: Fmt,
    /// `---:` rather than `---` in the alignment row.
    right: bool,
}

/// One column of a [`Table`] of rows `R`.
pub(crate) struct Column<'a, R> {
    /// The CSV header and the JSON key.
    name: &'static str,
    value: Box<dyn Fn(&R) -> Value + 'a>,
    json: bool,
    csv: Option<Fmt>,
    md: Option<Md>,
}

impl<'a, R> Column<'a, R> {
    /// A column whose cells are `value` of each row, in the JSON (under `name`); add it
    /// to the CSV and the Markdown with [`csv`](Self::csv) and [`md`](Self::md).
    pub(crate) fn new<V: Into<Value>>(name: &'static str, value: impl Fn(&R) -> V + 'a) -> Self {
        Column {
            name,
            value: Box::new(move |r| value(r).into()),
            json: true,
            csv: None,
            md: None,
        }
    }

    /// A column that is not in the JSON (only in the CSV or the Markdown it is added to).
    pub(crate) fn text<V: Into<Value>>(name: &'static str, value: impl Fn(&R) -> V + 'a) -> Self {
        Column {
            json: false,
            ..Column::new(name, value)
        }
    }

    /// A Markdown-only column headed `header`, printed as it is.
    pub(crate) fn md_only<V: Into<Value>>(
        header: impl Into<String>,
        value: impl Fn(&R) -> V + 'a,
    ) -> Self {
        Column::text("", value).md(header, Fmt::PLAIN)
    }

    /// In the CSV (headed by the column's name), printed with `fmt`.
    pub(crate) fn csv(mut self, fmt: Fmt) -> Self {
        self.csv = Some(fmt);
        self
    }

    /// In the Markdown, headed `header`, printed with `fmt`, left-aligned.
    pub(crate) fn md(mut self, header: impl Into<String>, fmt: Fmt) -> Self {
        self.md = Some(Md {
            header: header.into(),
            fmt,
            right: false,
        });
        self
    }

    /// Right-aligns the Markdown column (`---:`).
    pub(crate) fn right(mut self) -> Self {
        if let Some(md) = &mut self.md {
            md.right = true;
        }
        self
    }
}

/// Rows and the columns that describe them.
pub(crate) struct Table<'a, R> {
    rows: &'a [R],
    columns: Vec<Column<'a, R>>,
}

impl<'a, R> Table<'a, R> {
    /// The table of `rows`, described by `columns` (in their order in every output).
    pub(crate) fn new(rows: &'a [R], columns: Vec<Column<'a, R>>) -> Self {
        Table { rows, columns }
    }

    /// The rows.
    pub(crate) fn rows(&self) -> &'a [R] {
        self.rows
    }

    /// The CSV header line.
    pub(crate) fn csv_header(&self) -> String {
        let names: Vec<&str> = self
            .columns
            .iter()
            .filter(|c| c.csv.is_some())
            .map(|c| c.name)
            .collect();
        format!("{}\n", names.join(","))
    }

    /// The CSV lines of the rows (no header).
    pub(crate) fn csv_rows(&self) -> String {
        let mut s = String::new();
        for r in self.rows {
            let cells: Vec<String> = self
                .columns
                .iter()
                .filter_map(|c| Some(c.csv?.text(&(c.value)(r))))
                .collect();
            s.push_str(&cells.join(","));
            s.push('\n');
        }
        s
    }

    /// The CSV: header and rows.
    pub(crate) fn csv(&self) -> String {
        self.csv_header() + &self.csv_rows()
    }

    /// The Markdown table: header, alignment row and rows.
    pub(crate) fn markdown(&self) -> String {
        let md: Vec<(&Md, &Column<R>)> = self
            .columns
            .iter()
            .filter_map(|c| Some((c.md.as_ref()?, c)))
            .collect();
        let line = |cells: Vec<String>| format!("| {} |\n", cells.join(" | "));
        let mut s = line(md.iter().map(|(m, _)| m.header.clone()).collect());
        s.push('|');
        for (m, _) in &md {
            s.push_str(if m.right { "---:|" } else { "---|" });
        }
        s.push('\n');
        for r in self.rows {
            s.push_str(&line(
                md.iter().map(|(m, c)| m.fmt.text(&(c.value)(r))).collect(),
            ));
        }
        s
    }
}

/// The rows as a JSON array of objects.
impl<R> Serialize for Table<'_, R> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut seq = s.serialize_seq(Some(self.rows.len()))?;
        for r in self.rows {
            seq.serialize_element(&JsonRow(self, r))?;
        }
        seq.end()
    }
}

/// One row of a [`Table`] as a JSON object.
struct JsonRow<'t, 'a, R>(&'t Table<'a, R>, &'t R);

impl<R> Serialize for JsonRow<'_, '_, R> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(None)?;
        for c in self.0.columns.iter().filter(|c| c.json) {
            match (c.value)(self.1) {
                Value::Flatten(Json::Object(entries)) => {
                    for (k, v) in &entries {
                        map.serialize_entry(k, v)?;
                    }
                }
                Value::Flatten(Json::Invalid(msg)) => return Err(S::Error::custom(msg)),
                Value::Flatten(_) => {
                    return Err(S::Error::custom(format!(
                        "{}: only a struct or map can be flattened",
                        c.name
                    )));
                }
                v => map.serialize_entry(c.name, &v)?,
            }
        }
        map.end()
    }
}

/// `{w}x{h}`, the size cell of the Markdown tables.
pub(crate) fn size(width: u32, height: u32) -> String {
    format!("{width}x{height}")
}

/// Writes each `(name, body)` into `dir` (created if missing) atomically: a temporary
/// file, then a rename, so a reader never sees half a report.
pub(crate) fn write_files(dir: &Path, files: Vec<(&str, String)>) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    for (name, body) in files {
        let path = dir.join(name);
        let tmp = dir.join(format!(".{name}.tmp"));
        std::fs::write(&tmp, body).with_context(|| format!("writing {}", tmp.display()))?;
        std::fs::rename(&tmp, &path).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// A report's `{stem}.csv`, `{stem}.json` (pretty-printed) and `{stem}.md`, written
/// atomically into `dir`.
pub(crate) fn write_report<T: Serialize>(
    dir: &Path,
    stem: &str,
    csv: String,
    report: &T,
    md: String,
) -> Result<()> {
    write_files(
        dir,
        vec![
            (&format!("{stem}.csv"), csv),
            (
                &format!("{stem}.json"),
                serde_json::to_string_pretty(report)?,
            ),
            (&format!("{stem}.md"), md),
        ],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    struct R {
        name: &'static str,
        x: f64,
        y: Option<f32>,
        n: u32,
    }

    #[derive(serde::Serialize)]
    struct Extra {
        a: u32,
        b: Option<f64>,
    }

    #[derive(serde::Serialize)]
    struct Serde {
        name: &'static str,
        x: f64,
        #[serde(flatten)]
        extra: Extra,
        y: Option<f32>,
        n: u32,
    }

    fn rows() -> Vec<R> {
        vec![
            R {
                name: "a",
                x: 1.0 / 3.0,
                y: Some(0.1),
                n: 3,
            },
            R {
                name: "b",
                x: 2.0,
                y: None,
                n: 40,
            },
        ]
    }

    fn table(rows: &[R]) -> Table<'_, R> {
        Table::new(
            rows,
            vec![
                Column::new("name", |r: &R| r.name)
                    .csv(Fmt::PLAIN)
                    .md("name", Fmt::PLAIN),
                Column::md_only("size", |r: &R| size(r.n, 2 * r.n)),
                Column::new("x", |r: &R| r.x)
                    .csv(Fmt::PLAIN)
                    .md("x", Fmt::fixed(2))
                    .right(),
                Column::new("extra", |r: &R| {
                    Value::flatten(&Extra {
                        a: r.n,
                        b: r.y.map(f64::from),
                    })
                }),
                Column::new("y", |r: &R| r.y)
                    .csv(Fmt::fixed(3))
                    .md("y", Fmt::PLAIN.or("-")),
                Column::new("n", |r: &R| r.n).csv(Fmt::exp(1)),
            ],
        )
    }

    #[test]
    fn csv_and_markdown_print_each_column_in_its_format() {
        let rows = rows();
        let t = table(&rows);
        assert_eq!(
            t.csv(),
            "name,x,y,n\na,0.3333333333333333,0.100,3.0e0\nb,2,,4.0e1\n"
        );
        assert_eq!(
            t.markdown(),
            "| name | size | x | y |\n|---|---|---:|---|\n| a | 3x6 | 0.33 | 0.1 |\n| b | 40x80 | 2.00 | - |\n"
        );
    }

    #[test]
    fn json_is_what_serde_writes_for_the_same_struct() {
        let rows = rows();
        let want: Vec<Serde> = rows
            .iter()
            .map(|r| Serde {
                name: r.name,
                x: r.x,
                extra: Extra {
                    a: r.n,
                    b: r.y.map(f64::from),
                },
                y: r.y,
                n: r.n,
            })
            .collect();
        assert_eq!(
            serde_json::to_string_pretty(&table(&rows)).unwrap(),
            serde_json::to_string_pretty(&want).unwrap()
        );
        let empty: [R; 0] = [];
        assert_eq!(serde_json::to_string(&table(&empty)).unwrap(), "[]");
        assert_eq!(table(&empty).csv(), "name,x,y,n\n");
    }

    #[test]
    fn files_are_written_whole() {
        let dir = tempfile::tempdir().unwrap();
        let sub = dir.path().join("out");
        write_files(&sub, vec![("a.csv", "x\n".into())]).unwrap();
        assert_eq!(std::fs::read_to_string(sub.join("a.csv")).unwrap(), "x\n");
        assert!(!sub.join(".a.csv.tmp").exists());
    }
}
