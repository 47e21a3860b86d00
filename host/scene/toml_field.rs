//! The scene field at a position of a TOML document, so that an error serde reports by
//! position (an unknown field, a wrong type, an unknown variant) names the field as `--set`
//! spells it: `simulation.precision`, `inlet[0].speed_m_s`, `inlet[0].nozzle.radius_m`.

use std::ops::Range;
use toml_edit::{ImDocument, Item, TableLike, Value};

/// The dotted path of the innermost key or value of `text` whose span holds byte `offset`;
/// `None` when the text does not parse or the offset lies outside every key and value.
pub fn field_at(text: &str, offset: usize) -> Option<String> {
    let document = ImDocument::parse(text).ok()?;
    in_table(document.as_table(), offset, "")
}

fn holds(span: Option<Range<usize>>, offset: usize) -> bool {
    span.is_some_and(|s| s.contains(&offset) || (s.is_empty() && s.start == offset))
}

fn join(prefix: &str, key: &str) -> String {
    if prefix.is_empty() {
        key.to_string()
    } else {
        format!("{prefix}.{key}")
    }
}

fn in_table(table: &dyn TableLike, offset: usize, prefix: &str) -> Option<String> {
    for (key, item) in table.iter() {
        let path = join(prefix, key);
        if holds(table.key(key).and_then(|k| k.span()), offset) {
            return Some(path);
        }
        let found = match item {
            Item::Value(value) => in_value(value, offset, &path),
            // A table's span is its header; its entries carry their own spans.
            Item::Table(t) => in_table(t, offset, &path).or_else(|| holds(t.span(), offset).then(|| path.clone())),
            Item::ArrayOfTables(tables) => tables.iter().enumerate().find_map(|(i, t)| {
                let element = format!("{path}[{i}]");
                in_table(t, offset, &element).or_else(|| holds(t.span(), offset).then_some(element))
            }),
            Item::None => None,
        };
        if found.is_some() {
            return found;
        }
    }
    None
}

fn in_value(value: &Value, offset: usize, path: &str) -> Option<String> {
    if !holds(value.span(), offset) {
        return None;
    }
    let inner = match value {
        Value::InlineTable(t) => in_table(t, offset, path),
        Value::Array(a) => a.iter().enumerate().find_map(|(i, v)| in_value(v, offset, &format!("{path}[{i}]"))),
        _ => None,
    };
    Some(inner.unwrap_or_else(|| path.to_string()))
}

#[cfg(test)]
mod tests {
    use super::field_at;

    fn field_of(text: &str, marker: &str) -> Option<String> {
        field_at(text, text.find(marker).expect("marker in text"))
    }

    #[test]
    fn names_keys_values_and_elements_as_set_spells_them() {
        let text = "name = \"x\"\n[simulation]\nprecision = \"f16\"\n[[inlet]]\nspeed_m_s = 1.0\n\
                    [[inlet]]\nnozzle = { shape = \"circle\", radius_m = \"big\" }\nposition_m = [0.0, 0.2, \"z\"]\n";
        assert_eq!(field_of(text, "\"x\"").as_deref(), Some("name"));
        assert_eq!(field_of(text, "\"f16\"").as_deref(), Some("simulation.precision"));
        assert_eq!(field_of(text, "precision").as_deref(), Some("simulation.precision"));
        assert_eq!(field_of(text, "speed_m_s").as_deref(), Some("inlet[0].speed_m_s"));
        assert_eq!(field_of(text, "\"big\"").as_deref(), Some("inlet[1].nozzle.radius_m"));
        assert_eq!(field_of(text, "\"z\"").as_deref(), Some("inlet[1].position_m[2]"));
        assert_eq!(field_of(text, "[simulation]").as_deref(), Some("simulation"));
        assert_eq!(field_at("a = [", 0), None, "text that does not parse");
    }
}
