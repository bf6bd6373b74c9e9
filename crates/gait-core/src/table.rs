//! A table of typed columns: what a CSV file of a run holds, kept in memory so
//! the same values reach the CSV writer and Python's DataFrames.

/// One column's values.
#[derive(Debug, Clone, PartialEq)]
pub enum Column {
    Int(Vec<i64>),
    /// Printed with 6 decimals; a non-finite value is an empty cell.
    Num(Vec<f64>),
    /// An integer that may be absent (an empty cell).
    OptInt(Vec<Option<i64>>),
    Bool(Vec<bool>),
    Text(Vec<String>),
}

impl Column {
    pub fn len(&self) -> usize {
        match self {
            Column::Int(v) => v.len(),
            Column::Num(v) => v.len(),
            Column::OptInt(v) => v.len(),
            Column::Bool(v) => v.len(),
            Column::Text(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Row `i` as its CSV cell.
    fn cell(&self, i: usize) -> String {
        match self {
            Column::Int(v) => v[i].to_string(),
            Column::Num(v) if v[i].is_finite() => format!("{:.6}", v[i]),
            Column::Num(_) => String::new(),
            Column::OptInt(v) => v[i].map_or(String::new(), |x| x.to_string()),
            Column::Bool(v) => v[i].to_string(),
            Column::Text(v) => v[i].clone(),
        }
    }
}

/// Named columns of equal length, in file order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    pub columns: Vec<(String, Column)>,
}

impl Table {
    /// Adds a column (builder style).
    pub fn with(mut self, name: &str, column: Column) -> Self {
        self.columns.push((name.to_string(), column));
        self
    }

    pub fn rows(&self) -> usize {
        self.columns.first().map_or(0, |(_, c)| c.len())
    }

    /// The CSV text: a header line, then one line per row.
    pub fn to_csv(&self) -> Vec<u8> {
        let mut out = String::new();
        let names: Vec<&str> = self.columns.iter().map(|(n, _)| n.as_str()).collect();
        out.push_str(&names.join(","));
        out.push('\n');
        for i in 0..self.rows() {
            let cells: Vec<String> = self.columns.iter().map(|(_, c)| c.cell(i)).collect();
            out.push_str(&cells.join(","));
            out.push('\n');
        }
        out.into_bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_print_as_the_run_files_do() {
        let t = Table::default()
            .with("frame", Column::Int(vec![3, 4]))
            .with("v", Column::Num(vec![1.0 / 3.0, f64::NAN]))
            .with("bout", Column::OptInt(vec![Some(0), None]))
            .with("ok", Column::Bool(vec![true, false]))
            .with("why", Column::Text(vec!["a;b".into(), String::new()]));
        let csv = String::from_utf8(t.to_csv()).unwrap();
        assert_eq!(
            csv,
            "frame,v,bout,ok,why\n3,0.333333,0,true,a;b\n4,,,false,\n"
        );
        assert_eq!(Table::default().to_csv(), b"\n");
    }
}
