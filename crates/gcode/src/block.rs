//! One line of G-code (a block) as written: its words with their byte spans and its comments,
//! so a compensated line can be rebuilt by replacing only the numbers that change.
//!
//! Supported syntax (RS274/NGC subset that CAM post-processors emit): words are a letter and a
//! number with an optional sign and decimal point (`X-12.5`, `G1`, `F1200`), letters in either
//! case, spaces allowed between words and between letter and number; comments in parentheses
//! (not nested) or after `;`; a leading `/` (block delete) and a line holding only `%`.
//! Parameters and expressions (`#1`, `[1+2]`, `X#3`) are not supported and make a line malformed.

use std::ops::Range;

/// A word: upper-case letter, numeric value, the text the number was written as, and the span of
/// the whole word in the line.
#[derive(Debug, Clone, PartialEq)]
pub struct Word {
    pub letter: char,
    pub value: f64,
    pub number_text: String,
    pub span: Range<usize>,
}

/// A parsed line.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Block {
    pub words: Vec<Word>,
    /// Byte offset where the first comment starts (`(` or `;`), if any: new words are inserted
    /// before it.
    pub comment_start: Option<usize>,
}

impl Block {
    /// The first word with this letter.
    pub fn word(&self, letter: char) -> Option<&Word> {
        self.words.iter().find(|w| w.letter == letter)
    }

    pub fn value(&self, letter: char) -> Option<f64> {
        self.word(letter).map(|w| w.value)
    }

    /// Every G code on the line (e.g. 1.0, 90.0, 38.2).
    pub fn g_codes(&self) -> impl Iterator<Item = f64> + '_ {
        self.words
            .iter()
            .filter(|w| w.letter == 'G')
            .map(|w| w.value)
    }
}

/// Parse one line (without its line terminator). Errors say what is wrong and at which column
/// (1-based).
pub fn parse_block(line: &str) -> Result<Block, String> {
    let bytes = line.as_bytes();
    let mut block = Block::default();
    let mut i = 0;
    // skip a leading block-delete slash and a lone `%`
    while i < bytes.len() && bytes[i].is_ascii_whitespace() {
        i += 1;
    }
    if line.trim() == "%" {
        return Ok(block);
    }
    if i < bytes.len() && bytes[i] == b'/' {
        i += 1;
    }
    while i < bytes.len() {
        let c = bytes[i];
        if c.is_ascii_whitespace() {
            i += 1;
        } else if c == b'(' {
            block.comment_start.get_or_insert(i);
            match line[i..].find(')') {
                Some(end) => i += end + 1,
                None => return Err(format!("column {}: comment `(` is never closed", i + 1)),
            }
        } else if c == b';' {
            block.comment_start.get_or_insert(i);
            break;
        } else if c.is_ascii_alphabetic() {
            let start = i;
            let letter = (c as char).to_ascii_uppercase();
            i += 1;
            while i < bytes.len() && bytes[i] == b' ' {
                i += 1;
            }
            let number_start = i;
            if i < bytes.len() && (bytes[i] == b'+' || bytes[i] == b'-') {
                i += 1;
            }
            let digits_start = i;
            while i < bytes.len() && (bytes[i].is_ascii_digit() || bytes[i] == b'.') {
                i += 1;
            }
            let text = &line[number_start..i];
            let digits = &line[digits_start..i];
            if digits.is_empty() || digits == "." || digits.matches('.').count() > 1 {
                return Err(format!(
                    "column {}: word `{letter}` has no valid number after it",
                    start + 1
                ));
            }
            let value: f64 = text
                .parse()
                .map_err(|_| format!("column {}: `{letter}{text}` is not a number", start + 1))?;
            if letter != 'G' && letter != 'M' && block.words.iter().any(|w| w.letter == letter) {
                return Err(format!(
                    "column {}: word `{letter}` appears twice on the line",
                    start + 1
                ));
            }
            block.words.push(Word {
                letter,
                value,
                number_text: text.to_string(),
                span: start..i,
            });
        } else {
            return Err(format!("column {}: unexpected character `{}` (parameters and expressions are not supported)", i + 1, line[i..].chars().next().unwrap_or('?')));
        }
    }
    Ok(block)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_comments_and_spans() {
        let line = "N10 g1 X-12.5 y 3 F1200 (cut) ; end";
        let b = parse_block(line).unwrap();
        let letters: String = b.words.iter().map(|w| w.letter).collect();
        assert_eq!(letters, "NGXYF");
        assert_eq!(b.value('X'), Some(-12.5));
        assert_eq!(b.value('Y'), Some(3.0));
        assert_eq!(&line[b.word('X').unwrap().span.clone()], "X-12.5");
        assert_eq!(b.comment_start, Some(24));
        assert_eq!(b.g_codes().collect::<Vec<_>>(), vec![1.0]);
    }

    #[test]
    fn malformed_lines_name_the_column() {
        assert!(parse_block("G1 X").unwrap_err().contains("column 4"));
        assert!(parse_block("G1 X1 X2").unwrap_err().contains("twice"));
        assert!(parse_block("G1 X#1").unwrap_err().contains("column 4"));
        assert!(parse_block("G1 (open")
            .unwrap_err()
            .contains("never closed"));
        assert!(parse_block("G1 X1..2").unwrap_err().contains("column 4"));
        assert_eq!(parse_block("%").unwrap().words.len(), 0);
        assert_eq!(parse_block("/G0 X1").unwrap().value('X'), Some(1.0));
    }
}
