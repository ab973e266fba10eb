//! A declared range (`#[setting(range = "…")]`) read as a check: the text the window
//! shows is the one the check is generated from.
//!
//! Forms: intervals `(a, b]`, `[a, b]`, `[a, b)`, `(a, b)`; inclusive spans `a–b` and
//! `a..=b`; `≥ a` and `≤ b`. A bound is a number (digits may be grouped by spaces or
//! `_`: `1 000 000`), `inf`, a constant (`MAX_VSLS`) or another field of the struct
//! (`glossy_roughness_max`: the check reads its value). A note in parentheses after a
//! one-sided form (`≥ 0.5 (or inf)`) is for readers only.

use proc_macro2::{Literal, TokenStream};
use quote::{format_ident, quote};

/// One bound of a range.
#[derive(Clone, Debug, PartialEq)]
pub enum Bound {
    /// A number as written, grouping removed.
    Number(String),
    /// Infinity (no bound on that side).
    Inf,
    /// A constant or a field of the struct, by name.
    Name(String),
}

/// A parsed range: each side's bound and whether it is included.
#[derive(Clone, Debug, PartialEq)]
pub struct Range {
    /// The lower bound and whether it is included (None: unbounded).
    pub low: Option<(Bound, bool)>,
    /// The upper bound and whether it is included (None: unbounded).
    pub high: Option<(Bound, bool)>,
    /// Written as an inclusive span (`a–b`, `a..=b`).
    pub span: bool,
}

/// Parses a declared range, or says why it cannot be read.
pub fn parse(text: &str) -> Result<Range, String> {
    let t = text.trim();
    if let Some(rest) = t.strip_prefix('≥').or_else(|| t.strip_prefix(">=")) {
        return Ok(Range {
            low: Some((bound(drop_note(rest))?, true)),
            high: None,
            span: false,
        });
    }
    if let Some(rest) = t.strip_prefix('≤').or_else(|| t.strip_prefix("<=")) {
        return Ok(Range {
            low: None,
            high: Some((bound(drop_note(rest))?, true)),
            span: false,
        });
    }
    let open = t.chars().next();
    let close = t.chars().last();
    if let (Some(o @ ('(' | '[')), Some(c @ (')' | ']'))) = (open, close) {
        let inner = &t[1..t.len() - 1];
        let (a, b) = inner
            .split_once(',')
            .ok_or_else(|| format!("range {text:?}: an interval needs `a, b`"))?;
        return Ok(Range {
            low: Some((bound(a)?, o == '[')),
            high: Some((bound(b)?, c == ']')),
            span: false,
        });
    }
    let (a, b) = t
        .split_once("..=")
        .or_else(|| t.split_once('–'))
        .ok_or_else(|| {
            format!("range {text:?}: expected `(a, b]`, `[a, b]`, `a–b`, `a..=b`, `≥ a` or `≤ b`")
        })?;
    Ok(Range {
        low: Some((bound(a)?, true)),
        high: Some((bound(b)?, true)),
        span: true,
    })
}

/// `≥ 0.5 (or inf)` → `0.5`.
fn drop_note(s: &str) -> &str {
    s.split_once('(').map_or(s, |(b, _)| b)
}

fn bound(s: &str) -> Result<Bound, String> {
    let s: String = s.trim().chars().filter(|c| *c != ' ').collect();
    if s == "inf" || s == "∞" || s == "-inf" {
        return Ok(Bound::Inf);
    }
    let digits: String = s.chars().filter(|c| *c != '_').collect();
    if digits.parse::<f64>().is_ok() {
        return Ok(Bound::Number(digits));
    }
    let mut chars = s.chars();
    if chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_' || c == ':')
    {
        return Ok(Bound::Name(s));
    }
    Err(format!("bound {s:?} is not a number, `inf` or a name"))
}

impl Range {
    /// The check of `value` (an expression of the field's type, `float` when it is
    /// `f32`/`f64`): a block that returns `Err((key, reason))` out of the enclosing
    /// function when the value is outside. Written as `!(in range)`, so NaN is refused.
    pub fn check(
        &self,
        key: &str,
        value: &TokenStream,
        float: bool,
        fields: &[String],
    ) -> TokenStream {
        let mut tests = Vec::new();
        let mut shown = Vec::new();
        let mut args = Vec::new();
        for (side, b) in [(false, &self.low), (true, &self.high)] {
            let Some((b, closed)) = b else {
                continue;
            };
            let (expr, text) = self.bound_expr(b, float, fields, &mut args);
            let Some(expr) = expr else {
                // `inf`: closed admits infinity (no test), open refuses it.
                if !closed && float {
                    tests.push(quote! { #value.is_finite() });
                }
                shown.push(text);
                continue;
            };
            tests.push(match (side, closed) {
                (false, true) => quote! { #value >= #expr },
                (false, false) => quote! { #value > #expr },
                (true, true) => quote! { #value <= #expr },
                (true, false) => quote! { #value < #expr },
            });
            shown.push(text);
        }
        let reason = match (&self.low, &self.high) {
            (Some(_), None) => format!("{{}} is less than {}", shown[0]),
            (None, Some(_)) => format!("{{}} is more than {}", shown[0]),
            _ if self.span => format!("{{}} is not in {}..={}", shown[0], shown[1]),
            (Some((_, lc)), Some((_, hc))) => format!(
                "{{}} is not in {}{}, {}{}",
                if *lc { '[' } else { '(' },
                shown[0],
                shown[1],
                if *hc { ']' } else { ')' }
            ),
            (None, None) => unreachable!("a range has a bound"),
        };
        let test = if tests.is_empty() {
            quote! { true }
        } else {
            quote! { #(#tests)&&* }
        };
        quote! {
            if !(#test) {
                return ::core::result::Result::Err((
                    #key,
                    ::std::format!(#reason, #value #(, #args)*),
                ));
            }
        }
    }

    /// The range as `illume_transport::SettingBounds` (the table's view of the check).
    pub fn bounds(&self, float: bool, fields: &[String]) -> TokenStream {
        let side = |b: &Option<(Bound, bool)>, sign: f64| match b {
            None => quote! { ::core::option::Option::None },
            Some((b, closed)) => {
                let value = match b {
                    Bound::Inf => {
                        let inf = if sign < 0.0 {
                            quote! { ::core::f64::NEG_INFINITY }
                        } else {
                            quote! { ::core::f64::INFINITY }
                        };
                        quote! { ::illume_transport::SettingBound::Value(#inf) }
                    }
                    Bound::Number(n) => {
                        let lit = Literal::f64_unsuffixed(n.parse().expect("checked by parse"));
                        quote! { ::illume_transport::SettingBound::Value(#lit) }
                    }
                    Bound::Name(name) if fields.contains(name) => {
                        quote! { ::illume_transport::SettingBound::Field(#name) }
                    }
                    Bound::Name(name) => {
                        let path: syn::Path = syn::parse_str(name).expect("checked by parse");
                        quote! { ::illume_transport::SettingBound::Value(#path as f64) }
                    }
                };
                quote! { ::core::option::Option::Some((#value, #closed)) }
            }
        };
        let low = side(&self.low, -1.0);
        let high = side(&self.high, 1.0);
        let integer = !float;
        quote! {
            ::core::option::Option::Some(::illume_transport::SettingBounds {
                low: #low,
                high: #high,
                integer: #integer,
            })
        }
    }

    /// A bound as an expression (None for `inf`) and as the message shows it
    /// (`{}` placeholders take `args`, pushed here).
    fn bound_expr(
        &self,
        b: &Bound,
        float: bool,
        fields: &[String],
        args: &mut Vec<TokenStream>,
    ) -> (Option<TokenStream>, String) {
        match b {
            Bound::Inf => (None, "inf".to_owned()),
            Bound::Number(n) => {
                let lit = if float {
                    Literal::f64_unsuffixed(n.parse().expect("checked by parse"))
                } else {
                    n.parse::<Literal>().expect("a number is a literal")
                };
                (Some(quote! { #lit }), n.clone())
            }
            Bound::Name(name) if fields.contains(name) => {
                let ident = format_ident!("{name}");
                args.push(quote! { self.#ident });
                (Some(quote! { self.#ident }), format!("{name} = {{}}"))
            }
            Bound::Name(name) => {
                let path: syn::Path = syn::parse_str(name).expect("checked by parse");
                args.push(quote! { #path });
                (Some(quote! { #path }), "{}".to_owned())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_every_form_in_use() {
        let n = |s: &str| Bound::Number(s.to_owned());
        assert_eq!(
            parse("(0, 1]").unwrap(),
            Range {
                low: Some((n("0"), false)),
                high: Some((n("1"), true)),
                span: false
            }
        );
        assert_eq!(
            parse("1–1 000 000").unwrap(),
            Range {
                low: Some((n("1"), true)),
                high: Some((n("1000000"), true)),
                span: true
            }
        );
        assert_eq!(
            parse("2..=MAX").unwrap().high,
            Some((Bound::Name("MAX".into()), true))
        );
        assert_eq!(
            parse("≥ 0.5 (or inf)").unwrap(),
            Range {
                low: Some((n("0.5"), true)),
                high: None,
                span: false
            }
        );
        assert_eq!(parse("[0, inf)").unwrap().high, Some((Bound::Inf, false)));
        assert!(parse("streaming | deterministic").is_err());
    }
}
