//! What a pipeline needs from an adapter, checked before a device is created.
//!
//! wgpu reports a missing capability only when the pass that needs it is created, as a
//! validation error deep in a frame (`Format Rgba32Float is not renderable` on Mesa's GL
//! driver). Checking the adapter first lets device selection skip an adapter that cannot
//! run the pipeline, say why, and pick one that can.

use wgpu::{DownlevelFlags, Limits, TextureFormat, TextureUsages};

/// One texture format the pipeline uses, with the usages it needs.
#[derive(Debug, Clone, PartialEq)]
pub struct FormatNeed {
    /// Who needs it (a resource or pass name), for messages.
    pub what: String,
    /// The format.
    pub format: TextureFormat,
    /// The usages it needs (render attachment, sampled, storage, …).
    pub usages: TextureUsages,
    /// Formats that may stand in when the adapter lacks `format` (first usable wins).
    pub fallbacks: Vec<TextureFormat>,
}

/// One limit the pipeline needs at least.
#[derive(Debug, Clone, Copy)]
pub struct LimitNeed {
    /// The limit's name in wgpu's [`Limits`].
    pub name: &'static str,
    /// The smallest value that works.
    pub at_least: u64,
    /// Reads the limit.
    pub get: fn(&Limits) -> u64,
}

/// What a pipeline needs from an adapter (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct Requirements {
    /// Capabilities beyond WebGL2 that a pass uses, each with who needs it.
    pub downlevel: Vec<(DownlevelFlags, String)>,
    /// Texture formats and their usages.
    pub formats: Vec<FormatNeed>,
    /// Limits, each with who needs it.
    pub limits: Vec<(LimitNeed, String)>,
}

/// The outcome of checking an adapter.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Verdict {
    /// What the adapter lacks, one line each (empty: it fits).
    pub missing: Vec<String>,
    /// Format substitutions that make it fit: (wanted, used instead, who).
    pub fallbacks: Vec<(TextureFormat, TextureFormat, String)>,
}

impl Verdict {
    /// Whether the adapter can run the pipeline.
    pub fn fits(&self) -> bool {
        self.missing.is_empty()
    }

    /// The fallbacks as `wanted -> used (who)` lines.
    pub fn fallback_notes(&self) -> Vec<String> {
        self.fallbacks
            .iter()
            .map(|(want, used, who)| format!("{want:?} -> {used:?} ({who})"))
            .collect()
    }
}

/// Names of the downlevel flags ssbvb may need, for messages.
fn flag_name(flag: DownlevelFlags) -> String {
    const NAMES: &[(DownlevelFlags, &str)] = &[
        (DownlevelFlags::COMPUTE_SHADERS, "compute shaders"),
        (
            DownlevelFlags::VERTEX_STORAGE,
            "storage buffers in vertex shaders",
        ),
        (
            DownlevelFlags::FRAGMENT_STORAGE,
            "storage buffers in fragment shaders",
        ),
        (
            DownlevelFlags::FRAGMENT_WRITABLE_STORAGE,
            "writable storage in fragment shaders",
        ),
        (DownlevelFlags::INDIRECT_EXECUTION, "indirect draws"),
        (
            DownlevelFlags::READ_ONLY_DEPTH_STENCIL,
            "sampling a depth-stencil texture that is the read-only attachment",
        ),
        (
            DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES,
            "copies of depth textures to buffers",
        ),
    ];
    let named: Vec<_> = NAMES
        .iter()
        .filter(|(f, _)| flag.contains(*f))
        .map(|(_, n)| *n)
        .collect();
    if named.is_empty() {
        format!("{flag:?}")
    } else {
        named.join(" and ")
    }
}

fn usage_names(u: TextureUsages) -> String {
    let mut v = Vec::new();
    if u.contains(TextureUsages::RENDER_ATTACHMENT) {
        v.push("render attachment");
    }
    if u.contains(TextureUsages::TEXTURE_BINDING) {
        v.push("sampled");
    }
    if u.contains(TextureUsages::STORAGE_BINDING) {
        v.push("storage");
    }
    if u.contains(TextureUsages::COPY_SRC) {
        v.push("copy source");
    }
    if u.contains(TextureUsages::COPY_DST) {
        v.push("copy destination");
    }
    v.join(" + ")
}

impl Requirements {
    /// Adds a downlevel capability needed by `who` (once per flag and who).
    pub fn need_flags(&mut self, flags: DownlevelFlags, who: &str) {
        if !self.downlevel.iter().any(|(f, w)| *f == flags && w == who) {
            self.downlevel.push((flags, who.to_string()));
        }
    }

    /// Adds a format with its usages for `who`, merged with an earlier need of the same
    /// format by the same `who`.
    pub fn need_format(
        &mut self,
        format: TextureFormat,
        usages: TextureUsages,
        who: &str,
        fallbacks: &[TextureFormat],
    ) {
        if let Some(n) = self
            .formats
            .iter_mut()
            .find(|n| n.format == format && n.what == who)
        {
            n.usages |= usages;
            return;
        }
        self.formats.push(FormatNeed {
            what: who.to_string(),
            format,
            usages,
            fallbacks: fallbacks.to_vec(),
        });
    }

    /// Adds a limit for `who`; a larger need of the same limit replaces a smaller one.
    pub fn need_limit(&mut self, need: LimitNeed, who: &str) {
        if let Some((n, w)) = self.limits.iter_mut().find(|(n, _)| n.name == need.name) {
            if need.at_least > n.at_least {
                *n = need;
                *w = who.to_string();
            }
            return;
        }
        self.limits.push((need, who.to_string()));
    }

    /// Adds every need of `other` (several pipelines on one device).
    pub fn merge(&mut self, other: &Requirements) {
        for (f, who) in &other.downlevel {
            self.need_flags(*f, who);
        }
        for n in &other.formats {
            self.need_format(n.format, n.usages, &n.what, &n.fallbacks);
        }
        for (n, who) in &other.limits {
            self.need_limit(*n, who);
        }
    }

    /// Checks an adapter (see [`Requirements::check_with`]).
    pub fn check(&self, adapter: &wgpu::Adapter) -> Verdict {
        self.check_under(adapter, &adapter.limits())
    }

    /// [`Requirements::check`] against `limits` instead of the adapter's own (a device
    /// created with WebGPU's defaults); capabilities and formats are the adapter's.
    pub fn check_under(&self, adapter: &wgpu::Adapter, limits: &Limits) -> Verdict {
        let downlevel = adapter.get_downlevel_capabilities().flags;
        self.check_with(downlevel, limits, |f| {
            adapter.get_texture_format_features(f).allowed_usages
        })
    }

    /// Checks capabilities given as values (tests describe adapters that do not exist
    /// here): every missing flag, format usage and limit, one line each naming who needs it.
    pub fn check_with(
        &self,
        downlevel: DownlevelFlags,
        limits: &Limits,
        format_usages: impl Fn(TextureFormat) -> TextureUsages,
    ) -> Verdict {
        let mut v = Verdict::default();
        for (flags, who) in &self.downlevel {
            let lacking = *flags - downlevel;
            if !lacking.is_empty() {
                v.missing
                    .push(format!("{who} needs {}", flag_name(lacking)));
            }
        }
        for n in &self.formats {
            if format_usages(n.format).contains(n.usages) {
                continue;
            }
            match n
                .fallbacks
                .iter()
                .find(|f| format_usages(**f).contains(n.usages))
            {
                Some(f) => v.fallbacks.push((n.format, *f, n.what.clone())),
                None => {
                    let lacking = n.usages - format_usages(n.format);
                    v.missing.push(format!(
                        "{} needs {:?} as {} (not supported{})",
                        n.what,
                        n.format,
                        usage_names(lacking),
                        if n.fallbacks.is_empty() {
                            String::new()
                        } else {
                            format!(", nor its fallbacks {:?}", n.fallbacks)
                        }
                    ));
                }
            }
        }
        for (n, who) in &self.limits {
            let have = (n.get)(limits);
            if have < n.at_least {
                v.missing.push(format!(
                    "{who} needs {} >= {} (the device allows {have})",
                    n.name, n.at_least
                ));
            }
        }
        v
    }
}

/// Declares, for each named field of wgpu's [`Limits`], `pub const fn FIELD(n: u64) ->
/// LimitNeed`: that limit at least `n`.
macro_rules! limit_needs {
    ($($field:ident),* $(,)?) => {$(
        #[doc = concat!("`", stringify!($field), "` at least `n`.")]
        pub const fn $field(n: u64) -> LimitNeed {
            LimitNeed {
                name: stringify!($field),
                at_least: n,
                get: |l| l.$field as u64,
            }
        }
    )*};
}

limit_needs!(
    max_bind_groups,
    max_storage_buffers_per_shader_stage,
    max_texture_dimension_3d,
    max_color_attachment_bytes_per_sample,
    max_compute_invocations_per_workgroup,
);

/// WebGPU's bytes per sample of colour attachments `formats` bound together (in location
/// order): each format's render-target byte cost, placed at its component alignment.
pub fn color_attachment_bytes(formats: &[TextureFormat]) -> u64 {
    let mut total = 0u64;
    for f in formats {
        let align = u64::from(f.target_component_alignment().unwrap_or(1));
        total = total.div_ceil(align) * align + u64::from(f.target_pixel_byte_cost().unwrap_or(0));
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Asserts that `message` contains every one of `parts`.
    fn assert_contains_all(message: &str, parts: &[&str]) {
        for part in parts {
            assert!(message.contains(part), "{message:?} lacks {part:?}");
        }
    }

    fn needs() -> Requirements {
        let mut r = Requirements::default();
        r.need_flags(DownlevelFlags::COMPUTE_SHADERS, "pass `filter`");
        r.need_flags(DownlevelFlags::READ_ONLY_DEPTH_STENCIL, "pass `smooth`");
        r.need_format(
            TextureFormat::Rgba32Float,
            TextureUsages::RENDER_ATTACHMENT,
            "resource `entry`",
            &[],
        );
        r.need_format(
            TextureFormat::Depth32FloatStencil8,
            TextureUsages::RENDER_ATTACHMENT,
            "resource `depth_stencil`",
            &[TextureFormat::Depth24PlusStencil8],
        );
        r.need_limit(max_storage_buffers_per_shader_stage(8), "pass `filter`");
        r.need_limit(max_storage_buffers_per_shader_stage(10), "pass `filter2`");
        r.need_limit(max_storage_buffers_per_shader_stage(6), "pass `x`");
        r
    }

    #[test]
    fn a_full_adapter_fits_without_fallbacks() {
        let limits = Limits {
            max_storage_buffers_per_shader_stage: 16,
            ..Limits::default()
        };
        let v = needs().check_with(DownlevelFlags::all(), &limits, |_| TextureUsages::all());
        assert!(v.fits(), "{v:?}");
        assert!(v.fallbacks.is_empty());
    }

    #[test]
    fn a_gl_like_adapter_is_refused_with_every_reason() {
        // GLES-like: no read-only depth-stencil sampling, Rgba32Float not renderable, no
        // Depth32FloatStencil8 (the fallback is taken), 8 storage buffers per stage.
        let flags = DownlevelFlags::all() - DownlevelFlags::READ_ONLY_DEPTH_STENCIL;
        let limits = Limits {
            max_storage_buffers_per_shader_stage: 8,
            ..Limits::default()
        };
        let v = needs().check_with(flags, &limits, |f| match f {
            TextureFormat::Rgba32Float => TextureUsages::TEXTURE_BINDING,
            TextureFormat::Depth32FloatStencil8 => TextureUsages::empty(),
            _ => TextureUsages::all(),
        });
        assert!(!v.fits());
        assert_eq!(v.missing.len(), 3, "{:#?}", v.missing);
        assert_contains_all(&v.missing[0], &["pass `smooth`", "read-only"]);
        assert_contains_all(
            &v.missing[1],
            &["resource `entry`", "Rgba32Float", "render attachment"],
        );
        assert_contains_all(
            &v.missing[2],
            &[
                "max_storage_buffers_per_shader_stage >= 10",
                "pass `filter2`",
                "allows 8",
            ],
        );
        assert_eq!(
            v.fallbacks,
            vec![(
                TextureFormat::Depth32FloatStencil8,
                TextureFormat::Depth24PlusStencil8,
                "resource `depth_stencil`".to_string()
            )]
        );
    }
}
