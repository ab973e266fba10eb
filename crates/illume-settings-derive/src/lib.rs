//! `#[derive(Settings)]`: a technique's settings struct declares each field once — its
//! `///` doc, and a `#[setting(…)]` attribute with its default, unit, range and whether
//! a change applies at the next frame — and the derive writes the rest: `Default`, and
//! the table of field docs (`illume_transport::SettingsTable`) that tools show (the
//! window's tooltips, help texts) and that decides whether a change rebuilds the
//! technique. `#[derive(SettingValues)]` on an enum gives its values as the table
//! spells them (its serde `rename_all`), shown as the range of fields of that type.
//!
//! ```ignore
//! #[derive(Settings, serde::Serialize, serde::Deserialize)]
//! pub struct TracerSettings {
//!     /// Samples per pixel of a still. Noise falls as 1/√spp.
//!     #[setting(default = 256, range = "≥ 1")]
//!     pub spp: u32,
//!     /// Samples per pixel added each frame.
//!     #[setting(default = 4, range = "≥ 1", per_frame)]
//!     pub spp_per_frame: u32,
//! }
//! ```
//!
//! Field attributes: `default = EXPR` (absent: the type's `Default`), `unit = "…"`
//! (absent: the unit the name's suffix carries, `_ms`, `_deg`…, STYLE.md's naming
//! convention), `range = "…"` (the accepted values as people read them: `(0, 1]`,
//! `1–8`, `≥ 2`; absent: an enum's values — and the check: the derive writes
//! `validate_ranges()`, which refuses a value outside the declared range, NaN included;
//! the forms are in the `range` module), `min = CONST` / `max = CONST` (an integer
//! constant the code also uses that a bound of the range shows: a mismatch fails to
//! compile, so the text stays readable, `1–1 000 000`, and true), `per_frame` (read through the frame budget:
//! a change reaches a running technique without a rebuild). Fields marked
//! `#[serde(skip)]` are not settings and stay out of the table.

mod range;

use proc_macro::TokenStream;
use quote::quote;
use syn::{Data, DeriveInput, Expr, Fields, Lit, LitStr, Meta, parse_macro_input};

/// Derives `Default` and `illume_transport::SettingsTable` from one declaration per
/// field (see the crate documentation).
#[proc_macro_derive(Settings, attributes(setting))]
pub fn derive_settings(input: TokenStream) -> TokenStream {
    let input = parse_macro_input!(input as DeriveInput);
    settings(&input)
        .unwrap_or_else(syn::Error::into_compile_error)
        .into()
}

/// Derives `illume_transport::SettingValues` for a unit-variant enum: its values as serde
/// spells them (`rename_all`), joined with ` | `.
#[proc_macro_derive(SettingValues)]
pub fn derive_setting_values(input: TokenStream) -> TokenStream {
    let input = parse_macro_input!(input as DeriveInput);
    setting_values(&input)
        .unwrap_or_else(syn::Error::into_compile_error)
        .into()
}

/// One field's declaration.
struct Field {
    ident: syn::Ident,
    default: Option<Expr>,
    unit: Option<String>,
    range: Option<String>,
    /// Constants the range's lower and upper bound stand for (`min = …`, `max = …`).
    min: Option<Expr>,
    max: Option<Expr>,
    per_frame: bool,
    skip: bool,
    doc: String,
    ty: syn::Type,
}

fn settings(input: &DeriveInput) -> syn::Result<proc_macro2::TokenStream> {
    let Data::Struct(data) = &input.data else {
        return Err(syn::Error::new_spanned(input, "Settings is for structs"));
    };
    let Fields::Named(named) = &data.fields else {
        return Err(syn::Error::new_spanned(
            input,
            "Settings needs named fields",
        ));
    };
    let fields = named
        .named
        .iter()
        .map(field)
        .collect::<syn::Result<Vec<_>>>()?;
    let name = &input.ident;
    let defaults = fields.iter().map(|f| {
        let ident = &f.ident;
        match &f.default {
            Some(e) => quote! { #ident: #e },
            None => quote! { #ident: ::core::default::Default::default() },
        }
    });
    let names: Vec<String> = fields.iter().map(|f| f.ident.to_string()).collect();
    let docs = fields.iter().filter(|f| !f.skip).map(|f| {
        let key = f.ident.to_string();
        let doc = &f.doc;
        let unit = match f.unit.clone().or_else(|| suffix_unit(&key)) {
            Some(u) => quote! { ::core::option::Option::Some(#u) },
            None => quote! { ::core::option::Option::None },
        };
        let ty = &f.ty;
        let range = match &f.range {
            Some(r) => quote! { ::core::option::Option::Some(#r) },
            None => quote! { <#ty as ::illume_transport::SettingValues>::VALUES },
        };
        let bounds = match f.range.as_deref().map(range::parse) {
            Some(Ok(r)) => r.bounds(is_float(option_inner(&f.ty).unwrap_or(&f.ty)), &names),
            _ => quote! { ::core::option::Option::None },
        };
        let applies = if f.per_frame {
            quote! { ::illume_transport::Applies::PerFrame }
        } else {
            quote! { ::illume_transport::Applies::Rebuild }
        };
        quote! {
            ::illume_transport::SettingField {
                key: #key,
                doc: #doc,
                unit: #unit,
                range: #range,
                bounds: #bounds,
                applies: #applies,
            }
        }
    });
    let checks = fields
        .iter()
        .filter(|f| !f.skip)
        .filter_map(|f| f.range.as_ref().map(|r| (f, r)))
        .map(|(f, text)| {
            let parsed = range::parse(text).map_err(|e| syn::Error::new_spanned(&f.ident, e))?;
            let ident = &f.ident;
            let key = ident.to_string();
            let pins = [(&f.min, &parsed.low), (&f.max, &parsed.high)]
                .into_iter()
                .filter_map(|(c, b)| c.as_ref().map(|c| (c, b)))
                .map(|(constant, bound)| match bound {
                    Some((range::Bound::Number(n), _)) => {
                        let lit: proc_macro2::Literal = n.parse().map_err(|_| {
                            syn::Error::new_spanned(constant, "bound is not a literal")
                        })?;
                        let why = format!(
                            "{key}: the declared range {text:?} does not show {}",
                            quote!(#constant)
                        );
                        Ok(quote! {
                            const _: () = ::core::assert!((#constant) as i128 == #lit, #why);
                        })
                    }
                    _ => Err(syn::Error::new_spanned(
                        constant,
                        "min/max pin a numeric bound of the declared range",
                    )),
                })
                .collect::<syn::Result<Vec<_>>>()?;
            let check = match option_inner(&f.ty) {
                Some(inner) => {
                    let check = parsed.check(&key, &quote! { value }, is_float(inner), &names);
                    quote! {
                        if let ::core::option::Option::Some(value) = self.#ident {
                            #check
                        }
                    }
                }
                None => parsed.check(&key, &quote! { self.#ident }, is_float(&f.ty), &names),
            };
            Ok(quote! { #(#pins)* #check })
        })
        .collect::<syn::Result<Vec<_>>>()?;
    Ok(quote! {
        impl #name {
            /// Checks every field that declares a range against it (NaN is in no range),
            /// in the struct's order: the first field outside, and why.
            #[allow(
                unused_comparisons,
                clippy::absurd_extreme_comparisons,
                reason = "a declared bound may be the type's own limit"
            )]
            pub fn validate_ranges(
                &self,
            ) -> ::core::result::Result<(), (&'static str, ::std::string::String)> {
                #(#checks)*
                ::core::result::Result::Ok(())
            }
        }

        impl ::core::default::Default for #name {
            fn default() -> Self {
                Self { #(#defaults,)* }
            }
        }

        impl ::illume_transport::SettingsTable for #name {
            const FIELDS: &'static [::illume_transport::SettingField] = &[#(#docs,)*];
        }
    })
}

fn field(f: &syn::Field) -> syn::Result<Field> {
    let ident = f.ident.clone().expect("named fields");
    let mut out = Field {
        ident,
        default: None,
        unit: None,
        range: None,
        min: None,
        max: None,
        per_frame: false,
        skip: false,
        doc: String::new(),
        ty: f.ty.clone(),
    };
    let mut doc = String::new();
    for attr in &f.attrs {
        if attr.path().is_ident("doc") {
            if let Meta::NameValue(nv) = &attr.meta
                && let Expr::Lit(lit) = &nv.value
                && let Lit::Str(s) = &lit.lit
            {
                doc.push_str(s.value().trim());
                doc.push(' ');
            }
        } else if attr.path().is_ident("serde") {
            attr.parse_nested_meta(|m| {
                if m.path.is_ident("skip") {
                    out.skip = true;
                }
                // Other serde keys are serde's business.
                if m.input.peek(syn::Token![=]) {
                    let _: Expr = m.value()?.parse()?;
                }
                Ok(())
            })?;
        } else if attr.path().is_ident("setting") {
            attr.parse_nested_meta(|m| {
                if m.path.is_ident("default") {
                    out.default = Some(m.value()?.parse()?);
                } else if m.path.is_ident("unit") {
                    out.unit = Some(m.value()?.parse::<LitStr>()?.value());
                } else if m.path.is_ident("range") {
                    out.range = Some(m.value()?.parse::<LitStr>()?.value());
                } else if m.path.is_ident("min") {
                    out.min = Some(m.value()?.parse()?);
                } else if m.path.is_ident("max") {
                    out.max = Some(m.value()?.parse()?);
                } else if m.path.is_ident("per_frame") {
                    out.per_frame = true;
                } else {
                    return Err(m.error("expected default, unit, range, min, max or per_frame"));
                }
                Ok(())
            })?;
        }
    }
    if doc.trim().is_empty() && !out.skip {
        return Err(syn::Error::new_spanned(
            f,
            "every setting needs a `///` doc: its meaning, unit and trade-off",
        ));
    }
    out.doc = plain(doc.trim());
    Ok(out)
}

fn setting_values(input: &DeriveInput) -> syn::Result<proc_macro2::TokenStream> {
    let Data::Enum(data) = &input.data else {
        return Err(syn::Error::new_spanned(input, "SettingValues is for enums"));
    };
    let mut rename = String::new();
    for attr in input.attrs.iter().filter(|a| a.path().is_ident("serde")) {
        attr.parse_nested_meta(|m| {
            if m.path.is_ident("rename_all") {
                rename = m.value()?.parse::<LitStr>()?.value();
            } else if m.input.peek(syn::Token![=]) {
                let _: Expr = m.value()?.parse()?;
            }
            Ok(())
        })?;
    }
    let values: Vec<String> = data
        .variants
        .iter()
        .map(|v| spell(&v.ident.to_string(), &rename))
        .collect();
    let values = values.join(" | ");
    let name = &input.ident;
    Ok(quote! {
        impl ::illume_transport::SettingValues for #name {
            const VALUES: ::core::option::Option<&'static str> =
                ::core::option::Option::Some(#values);
        }
    })
}

/// A variant name as serde's `rename_all` spells it.
fn spell(variant: &str, rename: &str) -> String {
    let sep = match rename {
        "snake_case" => "_",
        "kebab-case" => "-",
        "lowercase" => "",
        _ => return variant.to_owned(),
    };
    let mut out = String::new();
    for (i, c) in variant.chars().enumerate() {
        if c.is_uppercase() && i > 0 {
            out.push_str(sep);
        }
        out.extend(c.to_lowercase());
    }
    out
}

/// `T` of an `Option<T>` field.
fn option_inner(ty: &syn::Type) -> Option<&syn::Type> {
    let syn::Type::Path(p) = ty else { return None };
    let last = p.path.segments.last()?;
    if last.ident != "Option" {
        return None;
    }
    let syn::PathArguments::AngleBracketed(args) = &last.arguments else {
        return None;
    };
    match args.args.first()? {
        syn::GenericArgument::Type(t) => Some(t),
        _ => None,
    }
}

/// Whether a field is a floating-point number (its bounds are then written as floats).
fn is_float(ty: &syn::Type) -> bool {
    matches!(ty, syn::Type::Path(p) if p.path.is_ident("f32") || p.path.is_ident("f64"))
}

/// The unit a field's name carries (STYLE.md: `budget_ms`, `radius_m`).
fn suffix_unit(key: &str) -> Option<String> {
    let units = [
        ("_ms", "ms"),
        ("_s", "s"),
        ("_m", "m"),
        ("_deg", "degrees"),
        ("_rad", "radians"),
        ("_min", "minutes"),
        ("_h", "hours"),
        ("_frames", "frames"),
        ("_fraction", "fraction"),
    ];
    units
        .iter()
        .find(|(s, _)| key.ends_with(s))
        .map(|(_, u)| (*u).to_owned())
}

/// A doc comment as plain text: intra-doc links by their text, backticks and escapes
/// removed.
fn plain(doc: &str) -> String {
    let mut out = String::with_capacity(doc.len());
    let mut rest = doc;
    while let Some(i) = rest.find("[`") {
        out.push_str(&rest[..i]);
        let after = &rest[i + 2..];
        let Some(end) = after.find("`]") else {
            out.push_str(&rest[i..]);
            rest = "";
            break;
        };
        out.push_str(&after[..end]);
        rest = &after[end + 2..];
        // `[text](path)`: drop the path.
        if rest.starts_with('(')
            && let Some(close) = rest.find(')')
        {
            rest = &rest[close + 1..];
        }
    }
    out.push_str(rest);
    out.replace("\\[", "[").replace("\\]", "]").replace('`', "")
}
