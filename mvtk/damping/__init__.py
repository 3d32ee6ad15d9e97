"""mvtk.damping (see DESIGN.md)."""

__all__: list[str] = []
