//! Command-line pieces the examples share.

use implicit_packing::containment::ContainerKind;

/// The container named on the command line (`ball`, `ellipsoid` or `box`).
pub fn container_kind(name: &str) -> Result<ContainerKind, String> {
    match name {
        "ball" => Ok(ContainerKind::Ball),
        "ellipsoid" => Ok(ContainerKind::Ellipsoid),
        "box" => Ok(ContainerKind::Box),
        other => Err(format!("unknown container `{other}`")),
    }
}
