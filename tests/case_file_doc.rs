//! `docs/case-file.md` against the code: its table of the `[contact]` settings lists exactly
//! the fields of `ContactSettings`, each with the default `ContactSettings::default()` has.

use internodes::contact::ContactSettings;

/// The rows `| key | default | ...` of the table after the line that starts with `heading`.
fn table_after(page: &str, heading: &str) -> Vec<(String, String)> {
    let rest = &page[page.find(heading).expect("the table's heading")..];
    rest.lines()
        .skip_while(|line| !line.starts_with('|'))
        .take_while(|line| line.starts_with('|'))
        .skip(2)
        .map(|line| {
            let cells: Vec<&str> = line.split('|').map(str::trim).collect();
            let plain = |cell: &str| cell.trim_matches('`').to_string();
            (plain(cells[1]), plain(cells[2]))
        })
        .collect()
}

#[test]
fn the_contact_settings_table_lists_every_field_with_its_default() {
    let page =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/case-file.md")).unwrap();
    let documented = table_after(&page, "Keys of `ContactSettings`");
    let defaults = serde_json::to_value(ContactSettings::default()).unwrap();
    let defaults = defaults.as_object().unwrap();

    let mut keys: Vec<&str> = documented.iter().map(|(key, _)| key.as_str()).collect();
    let mut fields: Vec<&str> = defaults.keys().map(String::as_str).collect();
    keys.sort();
    fields.sort();
    assert_eq!(
        keys, fields,
        "the documented keys against ContactSettings' fields"
    );

    for (key, default) in &documented {
        let value = &defaults[key.as_str()];
        let agrees = match (value.as_str(), value.as_f64(), value.as_bool()) {
            // A key with no default (`Option`) is documented as "none".
            _ if value.is_null() => default == "none",
            (Some(text), ..) => default.trim_matches('"') == text,
            (None, Some(number), _) => default.parse::<f64>().is_ok_and(|d| d == number),
            (None, None, Some(flag)) => default.parse::<bool>().is_ok_and(|d| d == flag),
            _ => false,
        };
        assert!(
            agrees,
            "{key}: documented default {default}, the code's {value}"
        );
    }
}
