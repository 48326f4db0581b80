//! The expected orders of convergence have one home, scenes/orders.toml: the Rust tests read it
//! through tests/common/orders.rs, the compare tool through its theory module
//! (compare/tests/test_orders_table.py shows the same of that side: a value changed in a copy
//! changes its verdicts' orders).

mod common;

use common::orders::{orders_path, Orders};
use sdcrack_core::problem::MultiplierSpace;

/// The repository's table as text.
fn table_text() -> String {
    std::fs::read_to_string(orders_path()).expect("scenes/orders.toml is readable")
}

/// `text` written as orders.toml into a fresh folder, and read back.
fn read_copy(text: &str) -> Result<Orders, String> {
    let dir = tempfile::tempdir().expect("temporary folder");
    let path = dir.path().join("orders.toml");
    std::fs::write(&path, text).expect("copy written");
    Orders::read(&path)
}

/// `text` with `old` replaced by `new`, where `old` stands exactly once.
fn edited(text: &str, old: &str, new: &str) -> String {
    assert_eq!(text.matches(old).count(), 1, "{old:?} once in the table");
    text.replace(old, new)
}

#[test]
fn the_tests_thresholds_are_the_tables_numbers() {
    let o = Orders::repository();
    let raw: toml::Table = table_text().parse().expect("TOML");
    let number = |section: &str, key: &str| {
        let table = section.split('.').fold(&raw, |t: &toml::Table, s| {
            t.get(s).and_then(toml::Value::as_table).expect(section)
        });
        table[key].as_float().expect(key)
    };
    assert_eq!(o.lowest_rate(1.0), 1.0 - number("rule", "margin"));
    assert_eq!(o.p1_u(0.5), number("p1", "u_l2") * 0.5);
    assert_eq!(o.p1_p(0.5), number("p1", "p_l2") * 0.5);
    assert_eq!(o.p1_px(1.0), number("p1", "p_x"));
    assert_eq!(o.open_crack.order, number("open_crack", "order"));
    assert_eq!(o.lambda.p0_jump, number("lambda", "p0_jump"));
    for m in MultiplierSpace::ALL {
        assert_eq!(o.paper_lambda(m), number("lambda.paper", m.name()));
    }
    assert_eq!(o.regularity.smooth_s, number("regularity", "smooth_s"));
    assert_eq!(o.regularity.singular_s, number("regularity", "singular_s"));
    assert_eq!(
        sdcrack::cli::RATE_LEVELS,
        o.rule.levels,
        "sdcrack check warns below the compare tool's number of levels"
    );
}

#[test]
fn a_value_changed_in_a_copy_of_the_table_changes_the_thresholds() {
    let text = table_text();
    let text = edited(&text, "margin = 0.1\n", "margin = 0.25\n");
    let text = edited(&text, "M1star = 0.75\n", "M1star = 0.8\n");
    let o = read_copy(&text).expect("the edited copy is a valid table");
    assert_eq!(o.lowest_rate(o.p1_u(1.0)), 2.0 - 0.25);
    assert_eq!(o.paper_lambda(MultiplierSpace::M1Star), 0.8);
    assert_eq!(
        o.paper_lambda(MultiplierSpace::M1),
        0.5,
        "the rest as it was"
    );
}

#[test]
fn a_number_the_tests_do_not_know_or_miss_is_refused() {
    let text = table_text();
    let unknown = edited(&text, "margin = 0.1\n", "margin = 0.1\nslack = 0.2\n");
    let e = read_copy(&unknown).expect_err("an unknown key");
    assert!(e.contains("slack"), "{e}");
    let missing = edited(&text, "p0_jump = 1.0\n", "");
    let e = read_copy(&missing).expect_err("a missing key");
    assert!(e.contains("p0_jump"), "{e}");
}
