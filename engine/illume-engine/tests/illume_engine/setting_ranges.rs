//! A declared range is the check (issue 32: each setting declared once): for every
//! technique and every setting that declares a range, a value just outside each bound
//! is refused naming the setting, a value at each closed bound passes the range, and
//! a value at an open bound is refused. Read from the settings tables, so a setting
//! added with a range is covered without a line here.

use illume_engine::{Config, TechniqueKind};
use illume_transport::{SettingBound, SettingBounds};

/// What `--set TABLE.KEY=VALUE` does with `value` on the default configuration: the
/// error's text, if any.
fn set(table: &str, key: &str, value: toml::Value) -> Result<(), String> {
    Config::default()
        .with_value(
            &format!("{table}.{key}={value}"),
            &[table.to_owned(), key.to_owned()],
            value,
        )
        .map(|_| ())
        .map_err(|e| e.to_string())
}

/// Whether `error` is the refusal of `table.key` by its declared range (the generated
/// messages), as opposed to a check across fields (`photon_stream.pool_size` must hold
/// one photon path of `max_bounces + 1` impacts).
fn refused_by_range(error: &str, table: &str, key: &str) -> bool {
    error.contains(&format!("{table}.{key}: "))
        && [" is not in ", " is less than ", " is more than "]
            .iter()
            .any(|phrase| error.contains(phrase))
}

/// A bound's value: a number, or the default of the field it names.
fn bound_value(defaults: &toml::Table, table: &str, bound: SettingBound) -> f64 {
    match bound {
        SettingBound::Value(v) => v,
        SettingBound::Field(other) => {
            let v = &defaults[table][other];
            v.as_float()
                .or_else(|| v.as_integer().map(|i| i as f64))
                .unwrap_or_else(|| panic!("{table}.{other} is not a number"))
        }
    }
}

/// The TOML value of `v` for a setting of whole (`integer`) or floating-point numbers;
/// None when TOML cannot hold it.
fn value(v: f64, integer: bool) -> Option<toml::Value> {
    if integer {
        (v >= i64::MIN as f64 && v <= i64::MAX as f64 && v.fract() == 0.0)
            .then_some(toml::Value::Integer(v as i64))
    } else {
        Some(toml::Value::Float(v))
    }
}

/// The nearest value beyond bound `b` (below it when `below`) that the setting's type
/// holds: the next integer, or a step of 10⁻⁶ relative (kept by `f32` and `f64` alike).
fn beyond(b: f64, below: bool, integer: bool) -> f64 {
    let step = if integer {
        1.0
    } else {
        b.abs().max(1.0) * 1e-6
    };
    if below { b - step } else { b + step }
}

#[test]
fn every_declared_range_is_checked_at_its_bounds() {
    let defaults = toml::Table::try_from(Config::default()).expect("the defaults serialise");
    let mut probes = 0;
    for &kind in TechniqueKind::ALL {
        let table = kind.name();
        for field in kind.setting_fields() {
            let Some(SettingBounds { low, high, integer }) = field.bounds else {
                continue;
            };
            let key = field.key;
            let range = field.range.unwrap_or("?");
            for (side, below) in [(low, true), (high, false)] {
                let Some((bound, closed)) = side else {
                    continue;
                };
                let b = bound_value(&defaults, table, bound);
                // At the bound: accepted by the range when closed, refused when open.
                if let Some(v) = value(b, integer) {
                    let result = set(table, key, v.clone());
                    if closed {
                        if let Err(e) = &result {
                            assert!(
                                !refused_by_range(e, table, key),
                                "{table}.{key} = {v} is on its range {range}, but: {e}"
                            );
                        }
                    } else {
                        let e = result.expect_err(&format!(
                            "{table}.{key} = {v} is outside its range {range}, but accepted"
                        ));
                        assert!(e.contains(key), "{table}.{key} = {v}: {e}");
                    }
                    probes += 1;
                }
                // Just beyond a finite bound: refused, naming the setting.
                if b.is_finite()
                    && !(integer && below && b <= 0.0)
                    && let Some(v) = value(beyond(b, below, integer), integer)
                {
                    let e = set(table, key, v.clone()).expect_err(&format!(
                        "{table}.{key} = {v} is outside its range {range}, but accepted"
                    ));
                    assert!(
                        refused_by_range(&e, table, key),
                        "{table}.{key} = {v}: refused for another reason: {e}"
                    );
                    probes += 1;
                }
            }
            // NaN is in no range.
            if !integer {
                let e = set(table, key, toml::Value::Float(f64::NAN))
                    .expect_err(&format!("{table}.{key} = nan accepted"));
                assert!(refused_by_range(&e, table, key), "{table}.{key} = nan: {e}");
                probes += 1;
            }
        }
    }
    assert!(
        probes > 40,
        "only {probes} probes: are the ranges still declared?"
    );
}
