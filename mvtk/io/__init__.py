"""mvtk.io (see DESIGN.md)."""

__all__: list[str] = []
