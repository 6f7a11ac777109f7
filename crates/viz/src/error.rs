//! The one error type of the crate.

/// Everything that can go wrong while making or writing a picture.
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
}

/// Converts a plotters error into [`VizError::Draw`]; plotters' error types borrow the backend's error
/// type, so they are kept as text.
pub(crate) fn draw_error(e: impl std::fmt::Display) -> VizError {
    VizError::Draw(e.to_string())
}
