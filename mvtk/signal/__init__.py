"""mvtk.signal (see DESIGN.md)."""

__all__: list[str] = []
