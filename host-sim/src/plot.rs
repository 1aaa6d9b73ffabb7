//! Plots (plotters, SVG and PNG).
