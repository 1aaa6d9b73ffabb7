//! `--set key.path=value` overrides, applied to the parsed TOML before deserialization so
//! they pass the same unknown-key and type checks as the file.

use super::SceneError;

/// Most levels a `--set` or `--range` key may have (`a.b.c` has 3). The deepest key of any
/// shipped scene has 3; the limit keeps an absurd key (60 000 levels) from nesting tables so deep
/// that building or reading them overflows the stack.
pub const MAX_KEY_DEPTH: usize = 16;

/// Check a dotted key's shape: no empty segment, at most [`MAX_KEY_DEPTH`] levels. A
/// longer key is named by its first levels only.
pub fn check_key(key: &str) -> Result<(), SceneError> {
    if key.is_empty() || key.split('.').any(str::is_empty) {
        return Err(SceneError::new(key, "empty key path segment"));
    }
    let depth = key.split('.').count();
    if depth > MAX_KEY_DEPTH {
        let head: Vec<&str> = key.split('.').take(3).collect();
        return Err(SceneError::new(
            format!("{}...", head.join(".")),
            format!("the key has {depth} levels; a scene key has at most {MAX_KEY_DEPTH}"),
        ));
    }
    Ok(())
}

/// Parse `key.path=value`: the value is read as a TOML value (`0.5`, `true`, `"rk45"`),
/// and taken as a bare string if it is not one (`rk45`).
pub fn parse_set(arg: &str) -> Result<(String, toml::Value), SceneError> {
    let (key, raw) = arg
        .split_once('=')
        .ok_or_else(|| SceneError::new(arg, "expected key.path=value"))?;
    let key = key.trim();
    check_key(key)?;
    let raw = raw.trim();
    let value = match format!("v = {raw}").parse::<toml::Table>() {
        Ok(mut t) => t
            .remove("v")
            .unwrap_or_else(|| toml::Value::String(raw.to_string())),
        Err(_) if is_integer_literal(raw) => {
            return Err(SceneError::new(
                key,
                format!(
                    "{raw} is an integer outside TOML's range, {} ..= {}",
                    i64::MIN,
                    i64::MAX
                ),
            ))
        }
        Err(_) => toml::Value::String(raw.to_string()),
    };
    Ok((key.to_string(), value))
}

/// True if `raw` reads as a decimal integer (sign, digits, `_` between digits): one TOML
/// refuses only because it does not fit in an i64.
fn is_integer_literal(raw: &str) -> bool {
    let digits = raw.strip_prefix(['+', '-']).unwrap_or(raw);
    digits.starts_with(|c: char| c.is_ascii_digit())
        && digits.ends_with(|c: char| c.is_ascii_digit())
        && digits.chars().all(|c| c.is_ascii_digit() || c == '_')
}

/// Parse every `--set` argument ([`parse_set`]); the first bad one is the error.
pub fn parse_sets(args: &[String]) -> Result<Vec<(String, toml::Value)>, SceneError> {
    args.iter().map(|s| parse_set(s)).collect()
}

/// Set `key` (dotted) to `value` in `table`, creating intermediate tables.
/// A key deeper than [`MAX_KEY_DEPTH`] is refused ([`check_key`]).
pub fn apply_set(table: &mut toml::Table, key: &str, value: toml::Value) -> Result<(), SceneError> {
    check_key(key)?;
    let mut parts: Vec<&str> = key.split('.').collect();
    let last = parts
        .pop()
        .ok_or_else(|| SceneError::new(key, "empty key"))?;
    let mut cur = table;
    let mut walked = String::new();
    for p in parts {
        if !walked.is_empty() {
            walked.push('.');
        }
        walked.push_str(p);
        let entry = cur
            .entry(p.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        cur = match entry {
            toml::Value::Table(t) => t,
            _ => {
                return Err(SceneError::new(
                    walked,
                    "is not a table, cannot set a key inside it",
                ))
            }
        };
    }
    cur.insert(last.to_string(), value);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_typed_and_bare_words_are_strings() {
        assert_eq!(parse_set("a.b=0.5").unwrap().1, toml::Value::Float(0.5));
        assert_eq!(parse_set("a=3").unwrap().1, toml::Value::Integer(3));
        assert_eq!(
            parse_set("a=rk45").unwrap().1,
            toml::Value::String("rk45".into())
        );
        assert!(parse_set("novalue").is_err());
        assert!(parse_set("a..b=1").is_err());
    }

    /// An integer beyond i64 says so, not "invalid type: string".
    #[test]
    fn an_integer_beyond_i64_is_refused_as_out_of_range() {
        for raw in [
            "9223372036854775808",
            "99999999999999999999",
            "-9223372036854775809",
        ] {
            let e = parse_set(&format!("sensor.seed={raw}")).unwrap_err();
            assert_eq!(e.key, "sensor.seed");
            assert!(e.reason.contains("outside TOML's range"), "{e}");
            assert!(e.reason.contains("9223372036854775807"), "{e}");
        }
        let top = parse_set("sensor.seed=9223372036854775807").unwrap().1;
        assert_eq!(top, toml::Value::Integer(i64::MAX));
        // a word is still a bare string
        assert_eq!(
            parse_set("a=12ab").unwrap().1,
            toml::Value::String("12ab".into())
        );
    }

    #[test]
    fn nested_tables_are_created_and_scalars_are_not_walked_through() {
        let mut t = toml::Table::new();
        apply_set(&mut t, "x.y.z", toml::Value::Integer(1)).unwrap();
        assert_eq!(t["x"]["y"]["z"].as_integer(), Some(1));
        let err = apply_set(&mut t, "x.y.z.w", toml::Value::Integer(1)).unwrap_err();
        assert_eq!(err.key, "x.y.z");
    }

    #[test]
    fn a_key_deeper_than_the_limit_is_refused_naming_the_limit() {
        let key = |n: usize| vec!["a"; n].join(".");
        assert!(parse_set(&format!("{}=1", key(MAX_KEY_DEPTH))).is_ok());
        let mut t = toml::Table::new();
        apply_set(&mut t, &key(MAX_KEY_DEPTH), toml::Value::Integer(1)).unwrap();
        for n in [MAX_KEY_DEPTH + 1, 60_000] {
            let e = parse_set(&format!("{}=1", key(n))).unwrap_err();
            assert_eq!(e.key, "a.a.a...", "{e}");
            assert!(e.reason.contains(&format!("{n} levels")), "{e}");
            assert!(e.reason.contains("at most 16"), "{e}");
            let e = apply_set(&mut toml::Table::new(), &key(n), toml::Value::Integer(1));
            assert!(e.unwrap_err().reason.contains("at most 16"));
        }
    }
}
