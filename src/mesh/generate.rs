//! Meshing a `.geo` script by calling gmsh, for case files that name one.

use std::path::Path;
use std::process::Command;

/// Runs `gmsh -3 GEO -format msh41 -o MSH [-setnumber NAME VALUE]...`. A 2D script meshes to
/// its surfaces (gmsh has no volume to fill). Returns gmsh's own message on failure.
pub fn mesh_geo(geo: &Path, msh: &Path, parameters: &[(String, f64)]) -> Result<(), String> {
    let mut command = Command::new("gmsh");
    command
        .arg("-3")
        .arg(geo)
        .args(["-format", "msh41", "-o"])
        .arg(msh);
    for (name, value) in parameters {
        command.arg("-setnumber").arg(name).arg(value.to_string());
    }
    let output = command.output().map_err(|e| {
        format!("could not run gmsh ({e}); install it (apt-get install gmsh) or give a .msh")
    })?;
    if !output.status.success() || !msh.exists() {
        let stderr = String::from_utf8_lossy(&output.stderr);
        let stdout = String::from_utf8_lossy(&output.stdout);
        let errors: Vec<&str> = stderr
            .lines()
            .chain(stdout.lines())
            .filter(|l| l.contains("Error"))
            .collect();
        return Err(if errors.is_empty() {
            format!("gmsh exited with {}", output.status)
        } else {
            errors.join("; ")
        });
    }
    Ok(())
}
