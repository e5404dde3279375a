//! Command-line pieces the examples share.

use implicit_packing::containment::ContainerShape;

/// The container named on the command line (`ball`, `ellipsoid` or `box`).
pub fn container_kind(name: &str) -> Result<ContainerShape, String> {
    match name {
        "ball" => Ok(ContainerShape::Ball),
        "ellipsoid" => Ok(ContainerShape::Ellipsoid),
        "box" => Ok(ContainerShape::Box),
        other => Err(format!("unknown container `{other}`")),
    }
}
