//! Name resolution and per-pass checks: turns a [`GraphDesc`] into a [`Graph`]
//! of ids, reporting every local error (names, usages, queues, kinds, outputs).

use crate::error::{ErrorKind, GraphError, GraphErrors};
use crate::registry::{ParamProblem, PassRegistry, suggest};
use crate::schema::{
    AccessMode, GraphDesc, ImageFormat, PassDecl, Queue, Repeat, ResourceDecl, Usage,
};
use crate::source::{Locator, Source, Span};
use serde::Serialize;
use std::collections::HashMap;

pub type PassId = usize;
pub type ResourceId = usize;

/// A declared resource.
#[derive(Debug, Clone, Serialize)]
pub struct Resource {
    pub name: String,
    pub decl: ResourceDecl,
    /// Span of the declaration's name.
    pub span: Span,
    /// For a version made by an in-place write (`"a -> b"`), the declared
    /// resource whose memory it is; `None` for declared resources.
    pub version_of: Option<ResourceId>,
    /// For a per-model copy made by [`crate::unroll`] (`gbuffer[1]`): the
    /// resource it copies (`gbuffer`). Kernels bind it under that name.
    pub copy_of: Option<ResourceId>,
}

/// One entry of a pass's `reads`, `writes` or `atomics`.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Access {
    pub resource: ResourceId,
    pub mode: AccessMode,
    pub usage: Usage,
    pub span: Span,
}

/// A declared pass with its accesses resolved.
#[derive(Debug, Clone, Serialize)]
pub struct Pass {
    pub name: String,
    pub kind: String,
    pub queue: Queue,
    pub params: ron::Value,
    pub accesses: Vec<Access>,
    /// Span of the pass's name.
    pub span: Span,
    pub repeat: Repeat,
    /// For a copy made by [`crate::unroll`]: the model it runs for.
    pub model_index: Option<u32>,
    /// Accesses written `"resource as name"`: the kernel binds `resource`
    /// under `name` (one pass kind used on two sets of resources).
    pub bind_as: Vec<(ResourceId, String)>,
    /// Keep naga's loop counters in this pass's shader
    /// ([`crate::schema::PassDecl::loop_bounding`]).
    pub loop_bounding: bool,
}

impl Pass {
    /// Whether this pass uses the rasterizer (has colour or depth attachments).
    pub fn is_raster(&self) -> bool {
        self.accesses
            .iter()
            .any(|a| matches!(a.usage, Usage::Color | Usage::Depth))
    }
}

/// A graph whose names all resolve.
#[derive(Debug, Clone, Serialize)]
pub struct Graph {
    pub name: String,
    #[serde(skip)]
    pub source: Source,
    pub resources: Vec<Resource>,
    pub passes: Vec<Pass>,
    pub outputs: Vec<(ResourceId, Span)>,
}

impl Graph {
    pub fn resource_id(&self, name: &str) -> Option<ResourceId> {
        self.resources.iter().position(|r| r.name == name)
    }
    /// The declared resource that owns `r`'s memory (`r` itself unless it is a version).
    pub fn physical(&self, r: ResourceId) -> ResourceId {
        self.resources[r].version_of.unwrap_or(r)
    }
    pub fn pass_id(&self, name: &str) -> Option<PassId> {
        self.passes.iter().position(|p| p.name == name)
    }
}

/// Resolves names and checks everything that concerns one declaration at a time.
pub fn resolve(
    desc: &GraphDesc,
    src: &Source,
    loc: &Locator,
    registry: &dyn PassRegistry,
) -> Result<Graph, GraphErrors> {
    let mut errors = Vec::new();

    let mut resources: Vec<Resource> = Vec::new();
    let mut by_name: HashMap<String, ResourceId> = HashMap::new();
    for (i, decl) in desc.resources.iter().enumerate() {
        let span = loc.span(&format!("resources[{i}].name"));
        if let Some(&first) = by_name.get(decl.name()) {
            let first_span = resources[first].span;
            errors.push(
                GraphError::new(
                    ErrorKind::DuplicateName,
                    src,
                    span,
                    format!("resource `{}` is declared twice", decl.name()),
                )
                .primary("declared again here")
                .label(first_span, "first declared here"),
            );
        } else {
            by_name.insert(decl.name().to_string(), resources.len());
        }
        if let ResourceDecl::Image { layers: 0, .. } = decl {
            errors.push(GraphError::new(
                ErrorKind::Size,
                src,
                loc.span(&format!("resources[{i}].layers")),
                format!("image `{}` has zero layers", decl.name()),
            ));
        }
        if let Some(why) = samples_problem(decl) {
            errors.push(GraphError::new(
                ErrorKind::Size,
                src,
                loc.span(&format!("resources[{i}].samples")),
                format!("image `{}` {why}", decl.name()),
            ));
        }
        resources.push(Resource {
            name: decl.name().to_string(),
            decl: decl.clone(),
            span,
            version_of: None,
            copy_of: None,
        });
    }
    declare_versions(desc, src, loc, &mut resources, &mut by_name, &mut errors);

    let mut passes = Vec::new();
    let mut pass_names: HashMap<&str, Span> = HashMap::new();
    for (i, decl) in desc.passes.iter().enumerate() {
        let span = loc.span(&format!("passes[{i}].name"));
        if let Some(&first) = pass_names.get(decl.name.as_str()) {
            errors.push(
                GraphError::new(
                    ErrorKind::DuplicateName,
                    src,
                    span,
                    format!("pass `{}` is declared twice", decl.name),
                )
                .primary("declared again here")
                .label(first, "first declared here"),
            );
        } else {
            pass_names.insert(&decl.name, span);
        }
        if !registry.contains(&decl.kind) {
            let mut e = GraphError::new(
                ErrorKind::UnknownPassKind,
                src,
                loc.span(&format!("passes[{i}].kind")),
                format!("pass `{}` has unknown kind `{}`", decl.name, decl.kind),
            )
            .primary("not in the pass registry");
            if let Some(s) = suggest(registry, &decl.kind) {
                e = e.help(format!("did you mean `{s}`?"));
            }
            errors.push(e);
        } else if let Err(problem) = registry.check_params(&decl.kind, &decl.params) {
            errors.push(param_error(i, decl, &problem, src, loc));
        }
        let mut bind_as = Vec::new();
        let accesses = resolve_accesses(
            i,
            decl,
            (&resources, &by_name),
            &mut bind_as,
            src,
            loc,
            &mut errors,
        );
        passes.push(Pass {
            name: decl.name.clone(),
            kind: decl.kind.clone(),
            queue: decl.queue,
            params: decl.params.clone(),
            accesses,
            span,
            repeat: decl.repeat,
            loop_bounding: decl.loop_bounding,
            model_index: None,
            bind_as,
        });
    }

    let mut outputs = Vec::new();
    for (i, name) in desc.outputs.iter().enumerate() {
        let span = loc.span(&format!("outputs[{i}]"));
        match by_name.get(name) {
            None => errors.push(unknown_resource(
                src,
                span,
                name,
                "listed as an output",
                &resources,
            )),
            Some(&r) => {
                let written = passes.iter().any(|p| {
                    p.accesses
                        .iter()
                        .any(|a| a.resource == r && a.mode.writes())
                });
                if !written {
                    errors.push(
                        GraphError::new(
                            ErrorKind::OutputNotWritten,
                            src,
                            span,
                            format!("output `{name}` is written by no pass"),
                        )
                        .label(resources[r].span, "declared here"),
                    );
                }
                outputs.push((r, span));
            }
        }
    }

    if errors.is_empty() {
        Ok(Graph {
            name: desc.name.clone(),
            source: src.clone(),
            resources,
            passes,
            outputs,
        })
    } else {
        Err(GraphErrors(errors))
    }
}

fn resolve_accesses(
    pass_index: usize,
    decl: &PassDecl,
    (resources, by_name): (&[Resource], &HashMap<String, ResourceId>),
    bind_as: &mut Vec<(ResourceId, String)>,
    src: &Source,
    loc: &Locator,
    errors: &mut Vec<GraphError>,
) -> Vec<Access> {
    let lists = [
        (AccessMode::Read, &decl.reads),
        (AccessMode::Write, &decl.writes),
        (AccessMode::Atomic, &decl.atomics),
    ];
    let mut out: Vec<Access> = Vec::new();
    for (mode, list) in lists {
        for (j, entry) in list.iter().enumerate() {
            let span = loc.span(&format!("passes[{pass_index}].{}[{j}]", mode.field()));
            let (entry, alias) = match entry.split_once(" as ") {
                Some((e, name)) => (e.trim(), Some(name.trim())),
                None => (entry.as_str(), None),
            };
            let (entry, renamed) = match entry.split_once("->") {
                Some((old, new)) => (old.trim(), Some(new.trim())),
                None => (entry, None),
            };
            if renamed.is_some() && alias.is_some() {
                errors.push(GraphError::new(
                    ErrorKind::BadAccess,
                    src,
                    span,
                    format!(
                        "pass `{}`: an in-place write `a -> b` binds under `a`'s name; it takes no `as`",
                        decl.name
                    ),
                ));
                continue;
            }
            if renamed.is_some() && mode != AccessMode::Write {
                errors.push(GraphError::new(
                    ErrorKind::BadAccess,
                    src,
                    span,
                    format!(
                        "pass `{}`: `a -> b` versions are made by `writes` only",
                        decl.name
                    ),
                ));
                continue;
            }
            let (usage, name) = match entry.split_once(':') {
                None => (Usage::Storage, entry),
                Some((prefix, name)) => match Usage::PREFIXES.iter().find(|(p, _)| *p == prefix) {
                    Some((_, u)) => (*u, name),
                    None => {
                        let known: Vec<_> = Usage::PREFIXES.iter().map(|(p, _)| *p).collect();
                        errors.push(
                            GraphError::new(
                                ErrorKind::BadAccess,
                                src,
                                span,
                                format!(
                                    "pass `{}`: unknown usage `{prefix}` in `{entry}`",
                                    decl.name
                                ),
                            )
                            .help(format!("usages are {}", known.join(", "))),
                        );
                        continue;
                    }
                },
            };
            let Some(&resource) = by_name.get(name) else {
                let what = format!("{} by pass `{}`", verb(mode), decl.name);
                errors.push(unknown_resource(src, span, name, &what, resources));
                continue;
            };
            let access = Access {
                resource,
                mode,
                usage,
                span,
            };
            if let Some(problem) = usage_problem(&access, &resources[resource].decl) {
                errors.push(GraphError::new(
                    ErrorKind::BadAccess,
                    src,
                    span,
                    format!("pass `{}`: `{entry}` {problem}", decl.name),
                ));
                continue;
            }
            if let Some(name) = alias {
                bind_as.push((resource, name.to_string()));
            }
            if let Some(new) = renamed {
                // An in-place write reads the old version and produces the new one.
                if let Some(&new_id) = by_name.get(new) {
                    out.push(Access {
                        resource,
                        mode: AccessMode::Read,
                        ..access
                    });
                    out.push(Access {
                        resource: new_id,
                        ..access
                    });
                }
                if !usage.allowed_on(decl.queue) {
                    errors.push(queue_error(pass_index, decl, usage, name, span, src, loc));
                }
                continue;
            }
            if !usage.allowed_on(decl.queue) {
                errors.push(queue_error(pass_index, decl, usage, name, span, src, loc));
                continue;
            }
            // One resource may be read and written by the same pass (in place);
            // any other repetition is a mistake.
            if let Some(prev) = out.iter().find(|a| a.resource == resource) {
                let in_place = matches!(
                    (prev.mode, mode),
                    (AccessMode::Read, AccessMode::Write) | (AccessMode::Write, AccessMode::Read)
                );
                if !in_place {
                    errors.push(
                        GraphError::new(
                            ErrorKind::DuplicateName,
                            src,
                            span,
                            format!("pass `{}` lists `{name}` more than once", decl.name),
                        )
                        .label(prev.span, "already listed here"),
                    );
                    continue;
                }
            }
            out.push(access);
        }
    }
    out
}

fn queue_error(
    pass_index: usize,
    decl: &PassDecl,
    usage: Usage,
    name: &str,
    span: Span,
    src: &Source,
    loc: &Locator,
) -> GraphError {
    GraphError::new(
        ErrorKind::QueueCannotAccess,
        src,
        span,
        format!(
            "pass `{}` runs on the {} queue, which cannot perform `{}` access to `{name}`",
            decl.name,
            decl.queue,
            usage.prefix()
        ),
    )
    .label(
        loc.span(&format!("passes[{pass_index}].queue")),
        "queue chosen here",
    )
    .help(queue_help(usage))
}

/// Registers every version named by an in-place write (`"usage:a -> b"`).
/// Versions may be used before the pass that makes them appears in the file,
/// so they are all declared before accesses are resolved.
fn declare_versions(
    desc: &GraphDesc,
    src: &Source,
    loc: &Locator,
    resources: &mut Vec<Resource>,
    by_name: &mut HashMap<String, ResourceId>,
    errors: &mut Vec<GraphError>,
) {
    let mut pending: Vec<(String, String, Span)> = Vec::new();
    for (i, pass) in desc.passes.iter().enumerate() {
        for (j, entry) in pass.writes.iter().enumerate() {
            if let Some((old, new)) = entry.split_once("->") {
                let old = old.trim();
                let old = old.split_once(':').map_or(old, |(_, n)| n);
                let span = loc.span(&format!("passes[{i}].writes[{j}]"));
                pending.push((old.to_string(), new.trim().to_string(), span));
            }
        }
    }
    // Chains (`a -> b`, `b -> c`) resolve in any order: repeat until stuck.
    while !pending.is_empty() {
        let before = pending.len();
        pending.retain(|(old, new, span)| {
            let Some(&old_id) = by_name.get(old) else {
                return true;
            };
            if let Some(&existing) = by_name.get(new) {
                errors.push(
                    GraphError::new(
                        ErrorKind::DuplicateName,
                        src,
                        *span,
                        format!("version `{new}` is already a name"),
                    )
                    .label(resources[existing].span, "first declared here"),
                );
                return false;
            }
            let root = resources[old_id].version_of.unwrap_or(old_id);
            by_name.insert(new.clone(), resources.len());
            resources.push(Resource {
                name: new.clone(),
                decl: resources[root].decl.clone(),
                span: *span,
                version_of: Some(root),
                copy_of: None,
            });
            false
        });
        if pending.len() == before {
            break;
        }
    }
    // Whatever is left renames something unknown; access resolution reports it.
}

/// A parameter the pass's kind rejects, at its key (an unknown key), its
/// value (a wrong type or range), or the whole `params` (not a map).
fn param_error(
    pass_index: usize,
    decl: &PassDecl,
    problem: &ParamProblem,
    src: &Source,
    loc: &Locator,
) -> GraphError {
    let params = format!("passes[{pass_index}].params");
    let (span, message) = if problem.key.is_empty() {
        (loc.span(&params), format!("params: {}", problem.message))
    } else {
        let path = format!("{params}.{}", problem.key);
        let span = match loc.key_span(&path) {
            Some(key) if problem.message.starts_with("unknown") => key,
            _ => loc.span(&path),
        };
        let message = format!("parameter `{}`: {}", problem.key, problem.message);
        (span, message)
    };
    GraphError::new(
        ErrorKind::BadParam,
        src,
        span,
        format!("pass `{}` ({}): {message}", decl.name, decl.kind),
    )
    .primary("rejected by the pass kind")
}

fn verb(mode: AccessMode) -> &'static str {
    match mode {
        AccessMode::Read => "read",
        AccessMode::Write => "written",
        AccessMode::Atomic => "updated atomically",
    }
}

fn unknown_resource(
    src: &Source,
    span: Span,
    name: &str,
    what: &str,
    resources: &[Resource],
) -> GraphError {
    let mut e = GraphError::new(
        ErrorKind::UnknownResource,
        src,
        span,
        format!("unknown resource `{name}` {what}"),
    )
    .primary("no resource of this name is declared");
    let closest = resources
        .iter()
        .map(|r| (strsim::jaro_winkler(&r.name, name), &r.name))
        .filter(|(s, _)| *s > 0.85)
        .max_by(|a, b| a.0.total_cmp(&b.0));
    if let Some((_, n)) = closest {
        e = e.help(format!("did you mean `{n}`?"));
    }
    e
}

/// Why an image's sample count is not one an attachment can have.
pub fn samples_problem(decl: &ResourceDecl) -> Option<String> {
    let ResourceDecl::Image {
        samples, layers, ..
    } = decl
    else {
        return None;
    };
    if ![1, 2, 4, 8].contains(samples) {
        return Some(format!("has {samples} samples, not 1, 2, 4 or 8"));
    }
    (*samples > 1 && *layers > 1)
        .then(|| "is multisampled and layered; multisampled images have one layer".into())
}

/// Why a usage does not fit the resource, if it does not.
fn usage_problem(a: &Access, decl: &ResourceDecl) -> Option<&'static str> {
    let format = match decl {
        ResourceDecl::Image { format, .. } => Some(*format),
        ResourceDecl::Buffer { .. } => None,
    };
    if format.is_none() && a.usage.image_only() {
        return Some("needs an image, but the resource is a buffer");
    }
    if format.is_some() && a.usage.buffer_only() {
        return Some("needs a buffer, but the resource is an image");
    }
    if a.usage == Usage::Depth && format != Some(ImageFormat::D32Float) {
        return Some("is a depth attachment, but the image has no depth format");
    }
    if a.usage == Usage::Color && format.is_some_and(ImageFormat::is_depth) {
        return Some("is a colour attachment, but the image has a depth format");
    }
    if decl.samples() > 1 && !matches!(a.usage, Usage::Color | Usage::Depth) {
        return Some("is not an attachment, but the image is multisampled (only draws use one)");
    }
    match a.mode {
        AccessMode::Atomic if a.usage != Usage::Storage => {
            Some("is atomic, which needs storage usage")
        }
        AccessMode::Write
            if matches!(a.usage, Usage::Uniform | Usage::Sampled | Usage::Indirect) =>
        {
            Some("is written, but that usage is read-only")
        }
        _ => None,
    }
}

fn queue_help(usage: Usage) -> &'static str {
    match usage {
        Usage::Color | Usage::Depth => {
            "attachments need the rasterizer: move the pass to `Graphics`"
        }
        _ => "transfer queues only copy: move the pass to `Graphics` or `AsyncCompute`",
    }
}
