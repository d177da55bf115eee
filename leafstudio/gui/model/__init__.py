"""gui/model."""
