//! Which field of a JSON document a parser error points at: serde_json reports a line and a
//! column, a user wants the field (`bezier.alpha[1][3]`) as well.

use crate::ModelError;

/// One open container on the way to the error.
enum Open {
    /// An object and the last key read in it (`expect_key`: the next string is a key).
    Object {
        key: Option<String>,
        expect_key: bool,
    },
    /// An array and the index of the element being read.
    Array { index: usize },
}

/// The dotted path of the value at byte `offset` of `text`: the keys and indices of the
/// containers open there, e.g. `bezier.alpha[1][3]`; empty at the top level. A lenient scan
/// (strings with escapes, brackets, commas, colons), so it works on text that does not parse.
pub(crate) fn path_at(text: &str, offset: usize) -> String {
    let bytes = text.as_bytes();
    let end = offset.min(bytes.len());
    let mut stack: Vec<Open> = Vec::new();
    let mut i = 0;
    while i < end {
        match bytes[i] {
            b'"' => {
                let start = i + 1;
                i += 1;
                while i < bytes.len() && bytes[i] != b'"' {
                    i += if bytes[i] == b'\\' { 2 } else { 1 };
                }
                let s = String::from_utf8_lossy(&bytes[start..i.min(bytes.len())]).into_owned();
                if let Some(Open::Object { key, expect_key }) = stack.last_mut() {
                    if *expect_key {
                        *key = Some(s);
                        *expect_key = false;
                    }
                }
            }
            b'{' => stack.push(Open::Object {
                key: None,
                expect_key: true,
            }),
            b'[' => stack.push(Open::Array { index: 0 }),
            b'}' | b']' => {
                stack.pop();
            }
            b',' => match stack.last_mut() {
                Some(Open::Object { expect_key, .. }) => *expect_key = true,
                Some(Open::Array { index }) => *index += 1,
                None => {}
            },
            _ => {}
        }
        i += 1;
    }
    let mut path = String::new();
    for open in &stack {
        match open {
            Open::Object { key: Some(k), .. } => {
                if !path.is_empty() {
                    path.push('.');
                }
                path.push_str(k);
            }
            Open::Object { key: None, .. } => {}
            Open::Array { index } => path.push_str(&format!("[{index}]")),
        }
    }
    path
}

/// Byte offset of a 1-based line and column (serde_json counts columns in bytes).
fn offset_of(text: &str, line: usize, column: usize) -> usize {
    let line_start: usize = text
        .split_inclusive('\n')
        .take(line.saturating_sub(1))
        .map(str::len)
        .sum();
    (line_start + column.saturating_sub(1)).min(text.len())
}

/// A serde_json error on `text` as a [`ModelError::Json`]: the field located from the line and
/// column, and a hint where JSON itself is the surprise (it has no NaN or infinity).
pub(crate) fn json_error(text: &str, origin: &str, e: &serde_json::Error) -> ModelError {
    let (line, column) = (e.line(), e.column());
    let full = e.to_string();
    let message = full
        .strip_suffix(&format!(" at line {line} column {column}"))
        .unwrap_or(&full)
        .to_string();
    let offset = offset_of(text, line, column);
    let mut field = path_at(text, offset);
    // A missing field is reported at the object's closing brace, after its last key: the
    // object's own path is the one to name.
    if message.starts_with("missing field") {
        field = path_at(text, offset.saturating_add(1));
    }
    let near = text.get(offset.saturating_sub(1)..).unwrap_or("");
    let near = near.trim_start_matches(|c: char| c == ':' || c.is_whitespace());
    let bare_non_number = ["NaN", "nan", "Infinity", "-Infinity", "inf", "-inf"]
        .iter()
        .any(|w| near.starts_with(w));
    let string_non_number = ["\"NaN\"", "\"nan\"", "\"inf\"", "\"Infinity\""]
        .iter()
        .any(|w| message.contains(w));
    let hint = if bare_non_number {
        let word: String = near
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '-')
            .collect();
        format!(", found {word} (JSON has no NaN or infinity: write a finite number)")
    } else if string_non_number {
        " (JSON has no NaN or infinity, and numbers are not quoted: write a finite number)".into()
    } else {
        String::new()
    };
    ModelError::Json {
        origin: origin.to_string(),
        line,
        column,
        field,
        message: message + &hint,
    }
}

/// Parses `text` as a versioned file of kind `what` ("gait", "gait library"): checks its
/// `schema_version` against `expected` before the schema, so that a file of another version
/// gets that error and not a field error, then deserializes it from the text (a type error
/// keeps its line and column).
pub(crate) fn parse_versioned<T: serde::de::DeserializeOwned>(
    text: &str,
    origin: &str,
    what: &str,
    expected: u32,
) -> crate::Result<T> {
    let raw: serde_json::Value =
        serde_json::from_str(text).map_err(|e| json_error(text, origin, &e))?;
    let version = raw
        .get("schema_version")
        .cloned()
        .unwrap_or(serde_json::Value::Null);
    if version.as_u64() != Some(u64::from(expected)) {
        return Err(ModelError::InvalidField {
            origin: origin.to_string(),
            field: "schema_version".into(),
            value: if version.is_null() {
                "(missing)".into()
            } else {
                version.to_string()
            },
            reason: format!("this build reads {what} schema version {expected}"),
        });
    }
    serde_json::from_str(text).map_err(|e| json_error(text, origin, &e))
}

/// Writes `value` to `path` as pretty JSON with a final newline (a validated gait or library).
pub(crate) fn write_pretty<T: serde::Serialize>(
    path: &std::path::Path,
    value: &T,
) -> crate::Result<()> {
    let text = serde_json::to_string_pretty(value).map_err(|e| ModelError::Parse {
        origin: path.display().to_string(),
        message: e.to_string(),
    })?;
    std::fs::write(path, text + "\n").map_err(|error| ModelError::Io {
        path: path.to_path_buf(),
        error,
    })
}

#[cfg(test)]
mod tests {
    use super::path_at;

    #[test]
    fn the_path_names_keys_and_indices_up_to_the_offset() {
        let text = r#"{"a": 1, "b": {"c": [0.5, [1, 2, NaN]]}, "d": "x"}"#;
        let at = |needle: &str| path_at(text, text.find(needle).expect("needle"));
        assert_eq!(at("NaN"), "b.c[1][2]");
        assert_eq!(at("1,"), "a");
        assert_eq!(at("0.5"), "b.c[0]");
        assert_eq!(at("\"x\""), "d");
        assert_eq!(path_at(text, 0), "");
    }

    #[test]
    fn keys_with_escaped_quotes_and_brackets_in_strings_do_not_confuse_the_scan() {
        let text = r#"{"na\"me": "[{,", "v": NaN}"#;
        assert_eq!(path_at(text, text.find("NaN").expect("NaN")), "v");
    }
}
