"""gui/qt."""
