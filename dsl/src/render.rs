//! Plain helpers for showing a span to a human: 1-based line and column, and the source line.
//! The CLI builds its rustc-style output from these; this module prints nothing.

use crate::Span;

/// 1-based (line, column) of a byte offset; columns count characters, not bytes.
pub fn line_col(source: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(source.len());
    let offset = (0..=offset)
        .rev()
        .find(|&o| source.is_char_boundary(o))
        .unwrap_or(0);
    let before = &source[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map(|i| i + 1).unwrap_or(0);
    let col = source[line_start..offset].chars().count() + 1;
    (line, col)
}

/// The full text of the line containing `span.start`, and the character range of the span on it
/// (clipped to that line).
pub fn line_of(source: &str, span: Span) -> (&str, usize, usize) {
    let start = span.start.min(source.len());
    let start = (0..=start)
        .rev()
        .find(|&o| source.is_char_boundary(o))
        .unwrap_or(0);
    let line_start = source[..start].rfind('\n').map(|i| i + 1).unwrap_or(0);
    let line_end = source[start..]
        .find('\n')
        .map(|i| start + i)
        .unwrap_or(source.len());
    let line = &source[line_start..line_end];
    let from = source[line_start..start].chars().count();
    let end = span.end.clamp(start, line_end);
    let end = (start..=end)
        .rev()
        .find(|&o| source.is_char_boundary(o))
        .unwrap_or(start);
    let width = source[start..end].chars().count().max(1);
    (line, from, width)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_and_columns_are_one_based() {
        let src = "a = 1\nbb = 2\n";
        assert_eq!(line_col(src, 0), (1, 1));
        assert_eq!(line_col(src, 6), (2, 1));
        assert_eq!(line_col(src, 11), (2, 6));
        assert_eq!(line_of(src, Span::new(6, 8)), ("bb = 2", 0, 2));
    }
}
