//! Tables as CSV and Markdown. Every file of the report is written with the workspace's atomic
//! write ([`rmt_runfolder::write_atomic`]: a temporary name and a rename), so a reader never sees
//! half a file.

/// One Markdown table of a [`TextTable`].
#[derive(Clone, Debug, PartialEq)]
pub struct Block {
    /// A sub-heading.
    pub caption: Option<String>,
    /// Column titles.
    pub header: Vec<String>,
    /// Cells, already formatted for reading.
    pub rows: Vec<Vec<String>>,
}

/// A table with a machine-readable CSV form and a readable Markdown form.
#[derive(Clone, Debug, PartialEq)]
pub struct TextTable {
    /// File stem (`benchmark_summary`).
    pub name: String,
    /// Heading.
    pub title: String,
    /// Paragraphs under the heading (units, sources, definitions).
    pub notes: Vec<String>,
    /// CSV column names.
    pub csv_header: Vec<String>,
    /// CSV cells.
    pub csv_rows: Vec<Vec<String>>,
    /// Markdown tables.
    pub blocks: Vec<Block>,
}

impl TextTable {
    /// The CSV text (RFC 4180 quoting, `\n` line ends).
    pub fn to_csv(&self) -> Vec<u8> {
        rmt_analysis::tables::csv_text(&self.csv_header, &self.csv_rows)
    }

    /// The Markdown text: a level-2 heading, the notes, then each block.
    pub fn to_markdown(&self) -> String {
        let mut out = format!("## {}\n\n", self.title);
        for note in &self.notes {
            out.push_str(note);
            out.push_str("\n\n");
        }
        out.push_str(&self.blocks_markdown());
        out
    }

    /// The blocks alone, each under its caption (a level-3 heading) when it has one.
    pub fn blocks_markdown(&self) -> String {
        let mut out = String::new();
        for block in &self.blocks {
            if let Some(caption) = &block.caption {
                out.push_str(&format!("### {caption}\n\n"));
            }
            out.push_str(&markdown_block(block));
            out.push('\n');
        }
        out
    }
}

/// A pipe table; the first column is left-aligned, the others right-aligned.
pub fn markdown_block(block: &Block) -> String {
    let escape = |s: &str| s.replace('|', "\\|");
    let mut out = format!(
        "| {} |\n",
        block
            .header
            .iter()
            .map(|h| escape(h))
            .collect::<Vec<_>>()
            .join(" | ")
    );
    out.push('|');
    for i in 0..block.header.len() {
        out.push_str(if i == 0 { "---|" } else { "---:|" });
    }
    out.push('\n');
    for row in &block.rows {
        let cells: Vec<String> = row
            .iter()
            .map(|c| {
                if c.is_empty() {
                    "–".into()
                } else {
                    escape(c)
                }
            })
            .collect();
        out.push_str(&format!("| {} |\n", cells.join(" | ")));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_print_as_csv_and_markdown() {
        let table = TextTable {
            name: "t".into(),
            title: "T".into(),
            notes: vec!["note".into()],
            csv_header: vec!["a".into(), "b".into()],
            csv_rows: vec![vec!["x,y".into(), "1".into()]],
            blocks: vec![Block {
                caption: None,
                header: vec!["a".into(), "b".into()],
                rows: vec![vec!["x|y".into(), String::new()]],
            }],
        };
        assert_eq!(table.to_csv(), b"a,b\n\"x,y\",1\n");
        assert_eq!(
            table.to_markdown(),
            "## T\n\nnote\n\n| a | b |\n|---|---:|\n| x\\|y | – |\n\n"
        );
    }
}
