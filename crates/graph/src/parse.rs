//! RON text → [`PipelineDesc`] for one file (its includes are [`crate::include`]'s): syntax
//! errors with line and column, and every unknown pass kind at once.

use crate::error::{GraphError, Loc, suggest};
use crate::kinds::KIND_NAMES;
use crate::locate::Locator;
use crate::schema::PipelineDesc;

/// The description of `src` alone (its includes unread), if it parses.
pub(crate) fn parse_only(src: &str) -> Option<PipelineDesc> {
    parse(src, "", &Locator::new(src)).ok()
}

/// RON → [`PipelineDesc`]. Unknown pass kinds are found by scanning the text, so all of
/// them are reported at once with suggestions, not only the first serde meets.
pub(crate) fn parse(src: &str, file: &str, loc: &Locator) -> Result<PipelineDesc, Vec<GraphError>> {
    let mut errors = Vec::new();
    for (found, pos, pass) in loc.kinds() {
        if !KIND_NAMES.contains(&found.as_str()) {
            errors.push(GraphError::UnknownKind {
                at: Loc {
                    file: file.to_string(),
                    pos: Some(pos),
                },
                pass: pass.unwrap_or_else(|| "?".to_string()),
                found: found.clone(),
                hint: suggest(&found, KIND_NAMES.iter().copied()),
            });
        }
    }
    match ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES)
        .from_str::<PipelineDesc>(src)
    {
        Ok(d) if errors.is_empty() => Ok(d),
        Ok(_) => Err(errors),
        Err(e) => {
            let pos = crate::locate::Position {
                line: e.span.start.line,
                col: e.span.start.col,
            };
            let already = matches!(e.code, ron::Error::NoSuchEnumVariant { outer: Some(ref o), .. } if o == "PassKind");
            if !already || errors.is_empty() {
                let message = match &e.code {
                    ron::Error::NoSuchEnumVariant {
                        expected, found, ..
                    } => format!(
                        "unexpected `{found}`{}",
                        suggest(found, expected.iter().copied())
                    ),
                    other => other.to_string(),
                };
                errors.push(GraphError::Syntax {
                    at: Loc {
                        file: file.to_string(),
                        pos: Some(pos),
                    },
                    message,
                });
            }
            errors.sort_by_key(|e| e.loc().pos);
            Err(errors)
        }
    }
}
