//! Reports: Markdown tables from one helper, CSV written by the `csv` crate.

use anyhow::Result;

/// A Markdown table: its header and rows of already formatted cells. The first `text` columns
/// are left-aligned (names, labels), the others right-aligned (numbers).
pub struct Table {
    head: Vec<String>,
    text: usize,
    rows: Vec<Vec<String>>,
}

impl Table {
    pub fn new<S: ToString>(head: &[S], text: usize) -> Self {
        Self { head: head.iter().map(ToString::to_string).collect(), text, rows: Vec::new() }
    }

    /// Adds a row (as many cells as the header has columns).
    pub fn row(&mut self, cells: Vec<String>) {
        debug_assert_eq!(cells.len(), self.head.len(), "{:?}", self.head);
        self.rows.push(cells);
    }

    /// The table as Markdown, ending with a newline.
    pub fn markdown(&self) -> String {
        let line = |cells: &[String]| format!("| {} |\n", cells.join(" | "));
        let align: Vec<String> =
            (0..self.head.len()).map(|i| if i < self.text { "---" } else { "---:" }.to_string()).collect();
        let mut s = line(&self.head);
        s.push_str(&format!("|{}|\n", align.join("|")));
        for r in &self.rows {
            s.push_str(&line(r));
        }
        s
    }
}

/// Rows of serde structs as CSV, with a header of their field names.
pub fn csv_rows<R: serde::Serialize>(rows: impl IntoIterator<Item = R>) -> Result<String> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r)?;
    }
    Ok(String::from_utf8(w.into_inner()?)?)
}

/// A CSV of string records (for columns known only at run time, such as a sweep's knobs).
pub fn csv_records(header: &[String], rows: &[Vec<String>]) -> Result<String> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(header)?;
    for r in rows {
        w.write_record(r)?;
    }
    Ok(String::from_utf8(w.into_inner()?)?)
}

/// `x` rounded to `places` decimals, for CSV cells that need no more digits than measured.
pub fn round(x: f64, places: i32) -> f64 {
    let f = 10f64.powi(places);
    (x * f).round() / f
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_align_names_left_and_numbers_right() {
        let mut t = Table::new(&["scene", "ms"], 1);
        t.row(vec!["a".into(), "1.5".into()]);
        assert_eq!(t.markdown(), "| scene | ms |\n|---|---:|\n| a | 1.5 |\n");
    }

    #[test]
    fn csv_quotes_what_it_must() {
        #[derive(serde::Serialize)]
        struct R {
            name: &'static str,
            v: f64,
        }
        let s = csv_rows([R { name: "a,\"b\"", v: round(2.0 / 3.0, 3) }]).unwrap();
        assert_eq!(s, "name,v\n\"a,\"\"b\"\"\",0.667\n");
        let s = csv_records(&["k".into()], &[vec!["x\ny".into()]]).unwrap();
        assert_eq!(s, "k\n\"x\ny\"\n");
    }
}
