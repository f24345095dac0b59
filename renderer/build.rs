//! Compiles every GLSL shader in `../shaders` to SPIR-V with shaderc.
//! A compile error fails the build and names the file and line.

use std::path::PathBuf;

fn main() {
    // Read at run time, not with env!(): a build script compiled for one checkout can be reused
    // by another sharing the target folder, and must look at that checkout's shaders.
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("CARGO_MANIFEST_DIR"));
    let shader_dir = manifest
        .parent()
        .expect("renderer/ has a parent")
        .join("shaders");
    let out_dir = PathBuf::from(std::env::var("OUT_DIR").expect("OUT_DIR"));
    println!("cargo:rerun-if-changed={}", shader_dir.display());

    let compiler = shaderc::Compiler::new().expect("shaderc compiler");
    let mut entries: Vec<PathBuf> = std::fs::read_dir(&shader_dir)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", shader_dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();

    let mut failures = Vec::new();
    for path in entries {
        println!("cargo:rerun-if-changed={}", path.display());
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
        let kind = match ext {
            "vert" => shaderc::ShaderKind::Vertex,
            "frag" => shaderc::ShaderKind::Fragment,
            "tesc" => shaderc::ShaderKind::TessControl,
            "tese" => shaderc::ShaderKind::TessEvaluation,
            "comp" => shaderc::ShaderKind::Compute,
            _ => continue, // .glsl files are includes
        };
        let source = std::fs::read_to_string(&path)
            .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
        let mut options = shaderc::CompileOptions::new().expect("shaderc options");
        options.set_target_env(
            shaderc::TargetEnv::Vulkan,
            shaderc::EnvVersion::Vulkan1_2 as u32,
        );
        options.set_optimization_level(shaderc::OptimizationLevel::Performance);
        options.set_warnings_as_errors();
        let include_dir = shader_dir.clone();
        options.set_include_callback(move |name, _ty, _from, _depth| {
            let p = include_dir.join(name);
            std::fs::read_to_string(&p)
                .map(|content| shaderc::ResolvedInclude {
                    resolved_name: p.display().to_string(),
                    content,
                })
                .map_err(|e| format!("{}: {e}", p.display()))
        });
        let file_name = path.display().to_string();
        match compiler.compile_into_spirv(&source, kind, &file_name, "main", Some(&options)) {
            Ok(artifact) => {
                let name = path.file_name().unwrap().to_string_lossy().to_string();
                std::fs::write(out_dir.join(format!("{name}.spv")), artifact.as_binary_u8())
                    .expect("write spv");
            }
            // shaderc's messages already read "file:line: error: ..."
            Err(e) => failures.push(e.to_string()),
        }
    }
    if !failures.is_empty() {
        // shaderc's first line is a generic "compilation error:"; the file:line lines follow.
        for line in failures.iter().flat_map(|f| f.lines()) {
            if line.contains(": error:") || line.contains(": warning:") {
                println!("cargo:warning={line}");
            }
        }
        panic!("shader compilation failed:\n{}", failures.join("\n"));
    }
}
