//! The table of the laws' options as Markdown, for the reference pages of the docs.

use super::{LAW_OPTIONS, OptionDefault, OptionKind, OptionSpec};

/// The values column: the range of a number, the names of a choice.
fn values(o: &OptionSpec) -> String {
    match (o.kind, o.range) {
        (OptionKind::Number, Some(r)) => r.interval(),
        (OptionKind::Number, None) => "any number".into(),
        (OptionKind::Flag, _) => "true, false".into(),
        (OptionKind::Choice(names), _) => names.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", "),
        (OptionKind::AdaptiveGain, _) => "(lambda_0, lambda_inf, lambda'_0), lambda_0 >= lambda_inf > 0".into(),
    }
}

fn default(o: &OptionSpec) -> String {
    match o.default {
        OptionDefault::Number(v) => format!("{v}"),
        OptionDefault::Flag(v) => format!("{v}"),
        OptionDefault::Choice(c) => format!("`{c}`"),
        OptionDefault::Unset => "unset".into(),
    }
}

fn scenario(o: &OptionSpec) -> String {
    match o.scenario_key() {
        Some(key) if o.scenario_unit() != o.unit => format!("`{key}` ({})", o.scenario_unit()),
        Some(key) => format!("`{key}`"),
        None => "-".into(),
    }
}

/// One row of the table.
fn row(o: &OptionSpec) -> String {
    let unit = if o.unit.is_empty() { "-" } else { o.unit };
    format!(
        "| `{}` | {} | {} | {} | {unit} | {} | {} |",
        o.name,
        o.laws.join(", "),
        values(o),
        default(o),
        scenario(o),
        o.doc.replace('|', "\\|")
    )
}

/// [`LAW_OPTIONS`] as a Markdown table: name (the Python keyword, ROS parameter and `vsinv
/// replay` flag), laws, values, default, unit, scenario key, meaning.
pub fn markdown_table() -> String {
    let mut lines = vec![
        "| option | laws | values | default | unit | scenario key | meaning |".to_string(),
        "|---|---|---|---|---|---|---|".to_string(),
    ];
    lines.extend(LAW_OPTIONS.iter().map(row));
    lines.join("\n") + "\n"
}
