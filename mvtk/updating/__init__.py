"""mvtk.updating (see DESIGN.md)."""

__all__: list[str] = []
