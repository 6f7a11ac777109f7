//! The one error type of the crate.

/// Everything that can go wrong while making or writing a picture or an animation.
#[derive(Debug, thiserror::Error)]
pub enum VizError {
    /// A width or height of zero, or larger than [`crate::Image::MAX_SIDE`].
    #[error("invalid image size {width}×{height}: each side must be between 1 and {max} pixels", max = crate::Image::MAX_SIDE)]
    InvalidSize { width: u32, height: u32 },

    /// A pixel buffer whose length is not 3 · width · height.
    #[error("pixel buffer for a {width}×{height} RGB image must hold {expected} bytes, found {found}")]
    BufferLength { width: u32, height: u32, expected: usize, found: usize },

    /// [`crate::Image::grid`] was given images of different sizes.
    #[error("grid tile {index} is {found_width}×{found_height}, expected {width}×{height} like tile 0")]
    GridTileSize { index: usize, width: u32, height: u32, found_width: u32, found_height: u32 },

    /// [`crate::Image::grid`] was given no images or zero columns.
    #[error("a grid needs at least one image and one column (got {n_images} images, {columns} columns)")]
    EmptyGrid { n_images: usize, columns: usize },

    /// An axis range that is not finite, empty, or not positive on a logarithmic axis.
    #[error("invalid {axis} range ({min}, {max}): {reason}")]
    InvalidRange { axis: &'static str, min: f64, max: f64, reason: &'static str },

    /// plotters failed while drawing a chart or text.
    #[error("drawing failed: {0}")]
    Draw(String),

    /// The PNG encoder failed, including I/O errors of the writer it was given.
    #[error("PNG encoding failed: {0}")]
    Png(#[from] png::EncodingError),

    /// What was handed to the glTF exporter cannot be written: a frame with the wrong number of
    /// vertices, a time that does not advance, a non-finite position, a triangle naming a missing vertex.
    #[error("glTF export: {object}: {reason}")]
    GltfInput { object: String, reason: String },

    /// The animation would not fit a GLB file, whose length is a 32-bit number.
    #[error(
        "glTF export: the file would be {bytes} bytes, more than a GLB file can hold (4 GiB); keep fewer frames"
    )]
    GltfTooLarge { bytes: u64 },

    /// Writing the GLB file failed.
    #[error("glTF export: writing failed: {0}")]
    GltfWrite(#[source] std::io::Error),

    /// Writing the USD stage failed.
    #[error("USD export: writing failed: {0}")]
    UsdWrite(#[source] std::io::Error),
}

/// Converts a plotters error into [`VizError::Draw`]; plotters' error types borrow the backend's error
/// type, so they are kept as text.
pub(crate) fn draw_error(e: impl std::fmt::Display) -> VizError {
    VizError::Draw(e.to_string())
}
