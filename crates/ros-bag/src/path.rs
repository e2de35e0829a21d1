//! Field paths: `pose.pose.position.x`, `orientation_covariance[0]`, `points[2].x`.

use crate::error::{Error, Result};

/// One step of a field path: a field name and, for an array field, the element's index.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Segment {
    pub name: String,
    pub index: Option<usize>,
}

/// Parses a field path; `key` names the mapping in errors.
pub(crate) fn parse(key: &str, field: &str) -> Result<Vec<Segment>> {
    let bad =
        |reason: &str| Error::BadFieldPath { key: key.to_owned(), field: field.to_owned(), reason: reason.to_owned() };
    if field.is_empty() {
        return Err(bad("empty"));
    }
    let mut out = Vec::new();
    for part in field.split('.') {
        let (name, index) = match part.find('[') {
            None => (part, None),
            Some(open) => {
                let Some(inner) = part[open + 1..].strip_suffix(']') else {
                    return Err(bad(&format!("`{part}`: an index is written `name[3]`")));
                };
                let Ok(i) = inner.parse::<usize>() else {
                    return Err(bad(&format!("`{part}`: the index `{inner}` is not a nonnegative integer")));
                };
                (&part[..open], Some(i))
            }
        };
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return Err(bad(&format!("`{part}` is not a field name (letters, digits, `_`)")));
        }
        out.push(Segment { name: name.to_owned(), index });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_parse_and_bad_ones_are_named() {
        let p = parse("k", "pose.covariance[35]").unwrap();
        assert_eq!(p.len(), 2);
        assert_eq!(p[1], Segment { name: "covariance".into(), index: Some(35) });
        for bad in ["", "a..b", "a[", "a[x]", "a[-1]", "a]", ".a", "a b"] {
            assert!(matches!(parse("k", bad), Err(Error::BadFieldPath { .. })), "{bad}");
        }
    }
}
