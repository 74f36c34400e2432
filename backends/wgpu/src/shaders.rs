//! Shader composition: every WGSL file under `shaders/` with a
//! `#define_import_path` is a naga_oil composable module; a pass's file is
//! composed into one naga module from there. Same scheme as the reflection
//! test (`passes/tests/wgsl.rs`, `composer()`), which checks every pass's
//! shader against its definition.

use naga::Module;
use naga::valid::{Capabilities, ShaderStages, ValidationFlags, Validator};
use naga_oil::compose::{
    ComposableModuleDescriptor, Composer, NagaModuleDescriptor, ShaderLanguage, ShaderType,
};
use std::path::{Path, PathBuf};

/// Capabilities a pass shader may ask for, and the wgpu feature each needs.
/// wgpu-core derives a device's naga capabilities from its features
/// (wgpu-core 30 `device/resource.rs`, `create_validator`): `SUBGROUP` gives
/// `SUBGROUP`, `SUBGROUP_BARRIER` gives `SUBGROUP_BARRIER`, `SHADER_F64`
/// gives `FLOAT64`, `SHADER_INT64` gives `SHADER_INT64`.
pub const CAPABILITY_FEATURES: [(Capabilities, wgpu::Features, &str); 4] = [
    (Capabilities::SUBGROUP, wgpu::Features::SUBGROUP, "SUBGROUP"),
    (
        Capabilities::SUBGROUP_BARRIER,
        wgpu::Features::SUBGROUP_BARRIER,
        "SUBGROUP_BARRIER",
    ),
    (
        Capabilities::FLOAT64,
        wgpu::Features::SHADER_F64,
        "SHADER_F64",
    ),
    (
        Capabilities::SHADER_INT64,
        wgpu::Features::SHADER_INT64,
        "SHADER_INT64",
    ),
];

fn all_capabilities() -> Capabilities {
    CAPABILITY_FEATURES
        .iter()
        .fold(Capabilities::empty(), |c, (cap, _, _)| c | *cap)
}

/// Where the WGSL lives: `$STRANDGRAPH_SHADERS`, else the checkout's `shaders/`,
/// else `shaders/` under the working directory (a copied checkout).
pub fn default_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os("STRANDGRAPH_SHADERS") {
        return dir.into();
    }
    let built = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shaders");
    if built.is_dir() {
        built
    } else {
        PathBuf::from("shaders")
    }
}

fn wgsl_files(dir: &Path, out: &mut Vec<PathBuf>) -> Result<(), String> {
    let read = std::fs::read_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut entries: Vec<PathBuf> = read.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            wgsl_files(&path, out)?;
        } else if path.extension().is_some_and(|e| e == "wgsl") {
            out.push(path);
        }
    }
    Ok(())
}

/// The shaders of one run.
pub struct Shaders {
    dir: PathBuf,
    composer: Composer,
}

/// A composed, validated pass shader.
pub struct Composed {
    pub module: Module,
    /// The capabilities it cannot validate without.
    pub needs: Capabilities,
}

impl Shaders {
    /// Adds every composable module under `dir`, imports first.
    pub fn load(dir: &Path) -> Result<Self, String> {
        let mut composer = Composer::default().with_capabilities(all_capabilities());
        let mut files = Vec::new();
        wgsl_files(dir, &mut files)?;
        let mut pending = Vec::new();
        for path in &files {
            let source =
                std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
            let (name, imports, _) = naga_oil::compose::get_preprocessor_data(&source);
            if let Some(name) = name {
                let imports: Vec<String> = imports.into_iter().map(|i| i.import).collect();
                let rel = path.strip_prefix(dir).unwrap_or(path);
                pending.push((name, rel.to_string_lossy().into_owned(), imports, source));
            }
        }
        while !pending.is_empty() {
            let ready = pending.iter().position(|(_, _, imports, _)| {
                imports
                    .iter()
                    .all(|i| composer.contains_module(i) || !pending.iter().any(|p| &p.0 == i))
            });
            let Some(ready) = ready else {
                let names: Vec<&str> = pending.iter().map(|p| p.1.as_str()).collect();
                return Err(format!(
                    "WGSL modules import each other in a cycle: {names:?}"
                ));
            };
            let (_, file, _, source) = pending.remove(ready);
            let added = composer.add_composable_module(ComposableModuleDescriptor {
                source: &source,
                file_path: &file,
                language: ShaderLanguage::Wgsl,
                ..Default::default()
            });
            if let Err(e) = added {
                return Err(format!("{file}: {}", e.emit_to_string(&composer)));
            }
        }
        Ok(Self {
            dir: dir.to_path_buf(),
            composer,
        })
    }

    /// Composes `file` (relative to the shader directory) and finds the
    /// capabilities it needs: each one without which it does not validate.
    pub fn compose(&mut self, file: &str) -> Result<Composed, String> {
        let path = self.dir.join(file);
        let source =
            std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let module = self
            .composer
            .make_naga_module(NagaModuleDescriptor {
                source: &source,
                file_path: file,
                shader_type: ShaderType::Wgsl,
                ..Default::default()
            })
            .map_err(|e| e.emit_to_string(&self.composer))?;
        let validates = |caps: Capabilities| {
            Validator::new(ValidationFlags::all(), caps)
                .subgroup_stages(ShaderStages::COMPUTE | ShaderStages::FRAGMENT)
                .validate(&module)
                .map(drop)
                .map_err(|e| format!("{file}: {e:?}"))
        };
        validates(all_capabilities())?;
        let needs = CAPABILITY_FEATURES
            .iter()
            .filter(|(cap, _, _)| validates(all_capabilities() - *cap).is_err())
            .fold(Capabilities::empty(), |c, (cap, _, _)| c | *cap);
        Ok(Composed { module, needs })
    }
}
