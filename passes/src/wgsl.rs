//! WGSL composition, shared by every GPU backend and the reflection test.
//!
//! Every WGSL file under `shaders/` with a `#define_import_path` is a
//! naga_oil composable module; a pass's file is composed into one naga
//! module from there (DESIGN.md: "Compose shared WGSL with a maintained
//! crate"). wgpu takes the module as is; ash translates it to SPIR-V.
//!
//! [`Composed::needs`] lists the naga capabilities the module cannot
//! validate without, which each backend maps to what it must enable (a wgpu
//! feature, a Vulkan feature and SPIR-V capability) and names in its errors.

use naga::Module;
use naga::valid::{Capabilities, ShaderStages, ValidationFlags, Validator};
use naga_oil::compose::{
    ComposableModuleDescriptor, Composer, NagaModuleDescriptor, ShaderLanguage, ShaderType,
};
use std::path::{Path, PathBuf};

/// The capabilities a pass shader may ask for. `SHADER_INT64_ATOMIC_MIN_MAX`
/// allows only `atomicMin`/`atomicMax` on storage `atomic<u64>` whose
/// result is unused; anything else needs `SHADER_INT64_ATOMIC_ALL_OPS`
/// (DESIGN.md, "Shaders").
pub const CAPABILITIES: [Capabilities; 6] = [
    Capabilities::SUBGROUP,
    Capabilities::SUBGROUP_BARRIER,
    Capabilities::FLOAT64,
    Capabilities::SHADER_INT64,
    Capabilities::SHADER_INT64_ATOMIC_MIN_MAX,
    Capabilities::SHADER_INT64_ATOMIC_ALL_OPS,
];

/// Every capability in [`CAPABILITIES`]; the composer validates with this.
pub fn all_capabilities() -> Capabilities {
    CAPABILITIES
        .iter()
        .fold(Capabilities::empty(), |c, cap| c | *cap)
}

/// Where the WGSL lives: `$STRANDGRAPH_SHADERS`, else the checkout's
/// `shaders/`, else `shaders/` under the working directory (a copied
/// checkout, as on the device machine).
pub fn default_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os("STRANDGRAPH_SHADERS") {
        return dir.into();
    }
    let built = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
    if built.is_dir() {
        built
    } else {
        PathBuf::from("shaders")
    }
}

/// Every `.wgsl` file under `dir`, sorted, recursively.
pub fn wgsl_files(dir: &Path) -> Result<Vec<PathBuf>, String> {
    let mut out = Vec::new();
    collect(dir, &mut out)?;
    Ok(out)
}

fn collect(dir: &Path, out: &mut Vec<PathBuf>) -> Result<(), String> {
    let read = std::fs::read_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut entries: Vec<PathBuf> = read.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            collect(&path, out)?;
        } else if path.extension().is_some_and(|e| e == "wgsl") {
            out.push(path);
        }
    }
    Ok(())
}

/// The shader directory with its composable modules loaded.
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
        let mut pending = Vec::new();
        for path in wgsl_files(dir)? {
            let source =
                std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
            let (name, imports, _) = naga_oil::compose::get_preprocessor_data(&source);
            if let Some(name) = name {
                let imports: Vec<String> = imports.into_iter().map(|i| i.import).collect();
                let rel = path.strip_prefix(dir).unwrap_or(&path);
                let rel = rel.to_string_lossy().replace('\\', "/");
                pending.push((name, rel, imports, source));
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

    /// The directory the shaders were loaded from.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Composes `file` (relative to the shader directory) without validating.
    pub fn module(&mut self, file: &str) -> Result<Module, String> {
        let path = self.dir.join(file);
        let source =
            std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        self.module_from_source(file, &source)
    }

    /// Composes `source` as if it were `file`, with the loaded imports.
    pub fn module_from_source(&mut self, file: &str, source: &str) -> Result<Module, String> {
        self.composer
            .make_naga_module(NagaModuleDescriptor {
                source,
                file_path: file,
                shader_type: ShaderType::Wgsl,
                ..Default::default()
            })
            .map_err(|e| e.emit_to_string(&self.composer))
    }

    /// Composes `file` and finds the capabilities it needs: each one without
    /// which it does not validate.
    pub fn compose(&mut self, file: &str) -> Result<Composed, String> {
        let module = self.module(file)?;
        validate(&module, all_capabilities()).map_err(|e| format!("{file}: {e}"))?;
        let mut needs = CAPABILITIES
            .iter()
            .filter(|cap| validate(&module, all_capabilities() - **cap).is_err())
            .fold(Capabilities::empty(), |c, cap| c | *cap);
        // Either int64-atomic tier allows `atomic<u64>`, so dropping one at
        // a time never fails: ask for the smaller tier that suffices.
        let (min_max, all_ops) = (
            Capabilities::SHADER_INT64_ATOMIC_MIN_MAX,
            Capabilities::SHADER_INT64_ATOMIC_ALL_OPS,
        );
        if validate(&module, all_capabilities() - min_max - all_ops).is_err() {
            let enough = validate(&module, all_capabilities() - all_ops).is_ok();
            needs |= if enough { min_max } else { all_ops };
        }
        Ok(Composed { module, needs })
    }
}

/// Validates `module` with `caps`, subgroup operations allowed in compute
/// and fragment stages.
pub fn validate(module: &Module, caps: Capabilities) -> Result<naga::valid::ModuleInfo, String> {
    Validator::new(ValidationFlags::all(), caps)
        .subgroup_stages(ShaderStages::COMPUTE | ShaderStages::FRAGMENT)
        .validate(module)
        .map_err(|e| format!("validation with {caps:?}: {e:?}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_pass_shader_composes_and_needs_are_minimal() {
        let mut shaders = Shaders::load(&default_dir()).unwrap();
        let composed = shaders.compose("common/clear.wgsl").unwrap();
        assert!(composed.needs.is_empty(), "{:?}", composed.needs);
        // The LOD's proportional reduction is done in f64, like the CPU kernel.
        let lod = shaders.compose("kulikov/lod.wgsl").unwrap();
        assert!(lod.needs.contains(Capabilities::FLOAT64), "{:?}", lod.needs);
        // atomicMin on atomic<u64> with the result unused: the smaller tier.
        let min64 = shaders.compose("bench/atomic_min64.wgsl").unwrap();
        assert!(
            min64
                .needs
                .contains(Capabilities::SHADER_INT64_ATOMIC_MIN_MAX | Capabilities::SHADER_INT64),
            "{:?}",
            min64.needs
        );
        assert!(
            !min64
                .needs
                .contains(Capabilities::SHADER_INT64_ATOMIC_ALL_OPS)
        );
    }

    #[test]
    fn a_missing_directory_is_an_error_naming_it() {
        let err = Shaders::load(Path::new("/nonexistent/shaders"))
            .err()
            .unwrap();
        assert!(err.contains("/nonexistent/shaders"), "{err}");
    }
}
