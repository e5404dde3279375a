//! Where in a scene's TOML text an error is: its line, its column and its dotted key, for
//! messages that point a person at it. The parser gives a byte span; the key path around it is
//! read back from the text (the toml crate keeps its own private).

/// Why a scene could not be read: the file, the position and the key of the first problem.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{source_name}: {}`{key}`: {message}", place(*.line, *.column))]
pub struct SceneError {
    /// The file, or `<built-in scene>`.
    pub source_name: String,
    /// 1-based line of the offending value or key (of the enclosing table for a missing
    /// key; line 1 when the key is missing at the top level); 0 for a scene given as a table
    /// ([`crate::scene::Scene::from_table`]), which has no lines.
    pub line: usize,
    /// 1-based column (in characters).
    pub column: usize,
    /// The dotted key, e.g. `solver.time_limit` or `shapes[0].semi_axes`.
    pub key: String,
    /// What is wrong.
    pub message: String,
}

/// `line L, column C: `, or nothing for a scene without lines (line 0).
fn place(line: usize, column: usize) -> String {
    if line == 0 {
        String::new()
    } else {
        format!("line {line}, column {column}: ")
    }
}

/// 1-based line and column (in characters) of a byte offset.
pub(crate) fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = text.get(..offset).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[line_start..].chars().count() + 1)
}

/// Converts a TOML error into a [`SceneError`], finding the key from the text around the
/// error's position (the toml crate keeps its key path private).
pub(crate) fn toml_error(text: &str, source_name: &str, e: &toml::de::Error) -> SceneError {
    let span = e.span().unwrap_or(0..0);
    let mut offset = span.start.min(text.len());
    // Byte offsets from the parser sit on character boundaries; make sure before slicing.
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let (line, column) = line_column(text, offset);
    let message = plain_types(e.message().trim());
    let table = table_path(text, offset);
    let key = if let Some(field) = missing_field(&message) {
        // A key missing at the top level comes with an empty span, one missing in a table
        // with the span of the table's header (or of its inline `{`).
        if span.is_empty() {
            field.to_string()
        } else {
            match inline_key(text, offset) {
                Some(outer) => join_key(&join_key(&table, &outer), field),
                None => join_key(&table, field),
            }
        }
    } else {
        match key_near(text, offset) {
            KeyNear::Header(path) => path,
            KeyNear::Key(k) => join_key(&table, &k),
            KeyNear::Nothing => table.clone(),
        }
    };
    // A mangled header (`[]`) or key can leave nothing to name: name the place instead.
    let key = if !key.is_empty() {
        key
    } else if !table.is_empty() {
        table
    } else {
        "<document>".to_string()
    };
    let message = table_not_string(&key, &message).unwrap_or(message);
    SceneError {
        source_name: source_name.to_string(),
        line,
        column,
        key,
        message,
    }
}

/// Serde's type names are Rust's: say "an integer" and "a number" to a person.
/// Our private `Raw…` structs are tables to a person, and an integer beyond 64 bits is out of
/// range rather than of an "invalid type".
pub(crate) fn plain_types(message: &str) -> String {
    let mut message = message
        .replace("expected i64", "expected an integer")
        .replace("expected u64", "expected a non-negative integer")
        .replace("expected f64", "expected a number")
        .replace("expected a sequence", "expected an array");
    while let Some(start) = message.find("expected struct Raw") {
        let rest = &message[start + "expected struct ".len()..];
        let end = rest
            .find(|c: char| !c.is_alphanumeric())
            .unwrap_or(rest.len());
        message.replace_range(
            start..start + "expected struct ".len() + end,
            "expected a table",
        );
    }
    // toml reports an integer beyond i64 in one of these two forms, depending on the path.
    let out_of_range = [
        ("invalid type: integer `", "` as i128, expected an integer"),
        ("invalid value: integer `", "`, expected an integer"),
    ];
    for (prefix, suffix) in out_of_range {
        if let Some(number) = message
            .strip_prefix(prefix)
            .and_then(|rest| rest.strip_suffix(suffix))
        {
            return format!(
                "{} is out of range: a whole number here is at most 9223372036854775807",
                crate::table::short_text(number)
            );
        }
    }
    message
}

/// A string where a table belongs (`container = "circle"`): show the two ways to write it.
fn table_not_string(key: &str, message: &str) -> Option<String> {
    let value = message
        .strip_prefix("invalid type: string ")?
        .strip_suffix(", expected a table")?;
    let inner = crate::table::short_text(value.trim_matches('"'));
    Some(if key == "container" {
        format!(
            "a container is a table, not the string {value}: write `container = {{ kind = \"{inner}\" }}`, or a [container] table with kind = \"{inner}\""
        )
    } else {
        format!("`{key}` is a table, not the string {value}")
    })
}

fn join_key(table: &str, key: &str) -> String {
    if table.is_empty() {
        key.to_string()
    } else {
        format!("{table}.{key}")
    }
}

/// The field named in serde's "missing field `x`".
fn missing_field(message: &str) -> Option<&str> {
    message
        .strip_prefix("missing field `")
        .and_then(|rest| rest.split('`').next())
}

/// The header name of a `[table]` or `[[array]]` line.
fn header_name(line: &str) -> Option<(&str, bool)> {
    let t = line.trim();
    if let Some(inner) = t.strip_prefix("[[") {
        return inner.split("]]").next().map(|n| (n.trim(), true));
    }
    t.strip_prefix('[')
        .and_then(|inner| inner.split(']').next())
        .map(|n| (n.trim(), false))
}

/// The dotted path of the table that holds byte `offset`: "" at the top level, `solver`,
/// `shapes[1]` (the second `[[shapes]]`, counted from 0).
fn table_path(text: &str, offset: usize) -> String {
    let mut path = String::new();
    let mut counts: Vec<(String, usize)> = Vec::new();
    let mut start = 0;
    for line in text.split_inclusive('\n') {
        if start > offset {
            break;
        }
        start += line.len();
        if let Some((name, array)) = header_name(line) {
            path = if array {
                let index = match counts.iter_mut().find(|(n, _)| n == name) {
                    Some((_, c)) => {
                        *c += 1;
                        *c
                    }
                    None => {
                        counts.push((name.to_string(), 0));
                        0
                    }
                };
                format!("{name}[{index}]")
            } else {
                name.to_string()
            };
        }
    }
    path
}

enum KeyNear {
    Header(String),
    Key(String),
    Nothing,
}

/// The key whose value (or name) sits at byte `offset`: the key before the last `=` on that
/// line before the offset, or the token at the offset (an unknown key), or for a value on a
/// continuation line of a multi-line array the key of the line that opened it.
fn key_near(text: &str, offset: usize) -> KeyNear {
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let line_end = text[offset..].find('\n').map_or(text.len(), |i| offset + i);
    let line = &text[line_start..line_end];
    if header_name(line).is_some() {
        return KeyNear::Header(table_path(text, offset));
    }
    let before = &text[line_start..offset];
    if let Some(eq) = before.rfind('=') {
        let inner = key_before(&before[..eq]);
        return match (inline_key(text, offset), inner) {
            (Some(outer), Some(inner)) if outer != inner => {
                KeyNear::Key(format!("{outer}.{inner}"))
            }
            (_, Some(inner)) => KeyNear::Key(inner),
            (Some(outer), None) => KeyNear::Key(outer),
            (None, None) => KeyNear::Nothing,
        };
    }
    let token: String = text[offset..line_end]
        .chars()
        .take_while(|c| *c != '=' && *c != '\n')
        .collect();
    let token = token.trim();
    if !token.is_empty() && text[offset..line_end].contains('=') {
        return KeyNear::Key(token.to_string());
    }
    // A continuation line: look upwards for the line with the key.
    for previous in text[..line_start].lines().rev() {
        if header_name(previous).is_some() {
            break;
        }
        if let Some(eq) = previous.find('=') {
            return key_before(&previous[..eq]).map_or(KeyNear::Nothing, KeyNear::Key);
        }
    }
    KeyNear::Nothing
}

/// For an offset inside an inline table (`shapes = [{count = 1, …}]`), the key of the line
/// that holds the inline table (`shapes`).
fn inline_key(text: &str, offset: usize) -> Option<String> {
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    // The span of a table missing a key starts at its `{`.
    let end = if text[offset..].starts_with('{') {
        offset + 1
    } else {
        offset
    };
    let before = &text[line_start..end];
    let eq = before.find('=')?;
    before[eq..]
        .contains('{')
        .then(|| key_before(&before[..eq]))?
}

/// The bare (possibly dotted) key just before a `=`.
fn key_before(s: &str) -> Option<String> {
    let s = s.trim_end();
    let start = s
        .char_indices()
        .rev()
        .find(|(_, c)| !(c.is_ascii_alphanumeric() || *c == '_' || *c == '-' || *c == '.'))
        .map_or(0, |(i, c)| i + c.len_utf8());
    let key = s[start..].trim();
    (!key.is_empty()).then(|| key.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_and_column_count_characters() {
        let text = "a = 1\nbé = 2\n";
        assert_eq!(line_column(text, 0), (1, 1));
        let offset = text.find('2').unwrap();
        assert_eq!(line_column(text, offset), (2, 6));
    }

    #[test]
    fn table_paths_count_arrays_from_zero() {
        let text = "x = 1\n[[shapes]]\ncount = 1\n[[shapes]]\ncount = 2\n[solver]\nthreads = 1\n";
        assert_eq!(table_path(text, 0), "");
        assert_eq!(
            table_path(text, text.find("count = 1").unwrap()),
            "shapes[0]"
        );
        assert_eq!(
            table_path(text, text.find("count = 2").unwrap()),
            "shapes[1]"
        );
        assert_eq!(table_path(text, text.find("threads").unwrap()), "solver");
    }
}
