//! Text tables on standard output, in one place: a command names its columns once (heading,
//! width, alignment) and hands over rows of cells it has already formatted. Cells are padded to
//! their column's width (never cut) and separated by one space.

/// How a column's cells sit in its width.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Align {
    Left,
    Right,
}

/// One column of a table.
#[derive(Debug, Clone)]
pub struct Column {
    heading: String,
    width: usize,
    align: Align,
}

/// A right-aligned column (numbers).
pub fn right(heading: impl Into<String>, width: usize) -> Column {
    Column { heading: heading.into(), width, align: Align::Right }
}

/// A left-aligned column (names).
pub fn left(heading: impl Into<String>, width: usize) -> Column {
    Column { heading: heading.into(), width, align: Align::Left }
}

/// A table's columns; it prints its header and its rows.
#[derive(Debug, Clone)]
pub struct Table {
    columns: Vec<Column>,
}

impl Table {
    pub fn new(columns: Vec<Column>) -> Self {
        Table { columns }
    }

    /// The heading line.
    pub fn header(&self) -> String {
        let headings: Vec<&str> = self.columns.iter().map(|c| c.heading.as_str()).collect();
        self.row(&headings)
    }

    /// One line of `cells`, one per column (missing cells are blank).
    pub fn row<S: AsRef<str>>(&self, cells: &[S]) -> String {
        let padded: Vec<String> = self
            .columns
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let cell = cells.get(i).map_or("", |s| s.as_ref());
                match c.align {
                    Align::Left => format!("{cell:<w$}", w = c.width),
                    Align::Right => format!("{cell:>w$}", w = c.width),
                }
            })
            .collect();
        padded.join(" ")
    }

    pub fn print_header(&self) {
        println!("{}", self.header());
    }

    pub fn print_row<S: AsRef<str>>(&self, cells: &[S]) {
        println!("{}", self.row(cells));
    }
}

/// A statistic's cell: five decimals, or `-` where no member defines it.
pub fn statistic(x: Option<f64>) -> String {
    x.map_or("-".into(), |x| format!("{x:.5}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_are_padded_to_their_column_and_never_cut() {
        let t = Table::new(vec![left("case", 6), right("value", 7)]);
        assert_eq!(t.header(), "case     value");
        assert_eq!(t.row(&["a", "1.5"]), "a          1.5");
        assert_eq!(t.row(&["longer-name", "2"]), "longer-name       2");
    }
}
