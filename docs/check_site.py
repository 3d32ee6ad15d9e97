"""Check the built documentation site: internal links and API coverage.

Usage: ``python docs/check_site.py docs/_build/html`` (run by ``make docs``).

- every relative ``href``/``src`` in every HTML page points at an existing file, and
  every ``#fragment`` at an ``id`` (or ``name``) in the target page;
- every public name (``__all__``) of every documented subpackage is in the site's
  ``objects.inv`` (documented in place, or re-exported from where it is documented);
- the install, getting-started, help and overview pages exist, the landing page shows
  its pictures and the gallery its figures.

Exits 1 with one line per problem, 0 when the site is clean. External links are not
followed (the build machines have no network); they are listed with ``--external``.
"""

from __future__ import annotations

import argparse
import sys
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

sys.path.insert(0, str(Path(__file__).resolve().parent / "_ext"))


class _Page(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.links: list[str] = []
        self.ids: set[str] = set()

    def handle_starttag(self, tag, attrs):
        d = dict(attrs)
        for key in ("id", "name"):
            if d.get(key):
                self.ids.add(d[key])
        for key in ("href", "src"):
            if d.get(key):
                self.links.append(d[key])


def _parse(path: Path) -> _Page:
    page = _Page()
    page.feed(path.read_text(encoding="utf-8", errors="replace"))
    return page


def check_links(root: Path) -> tuple[list[str], list[str]]:
    """Broken internal links as messages, and the external links seen."""
    pages = {p.resolve(): _parse(p) for p in root.rglob("*.html")}
    problems, external = [], []
    for path, page in pages.items():
        for link in page.links:
            parts = urlsplit(link)
            if parts.scheme in ("http", "https", "mailto", "ftp"):
                external.append(link)
                continue
            if parts.scheme == "data" or link.startswith("javascript:"):
                continue
            target = path if not parts.path else (path.parent / unquote(parts.path)).resolve()
            if target.is_dir():
                target = target / "index.html"
            rel = path.relative_to(root.resolve())
            if not target.exists():
                problems.append(f"{rel}: link {link!r} -> missing file")
                continue
            if parts.fragment and target.suffix == ".html":
                ids = pages[target].ids if target in pages else _parse(target).ids
                if unquote(parts.fragment) not in ids:
                    problems.append(f"{rel}: link {link!r} -> no anchor #{parts.fragment}")
    return problems, sorted(set(external))


def check_api(root: Path) -> list[str]:
    """Public names missing from objects.inv."""
    import importlib

    import mvtk_docs
    from sphinx.util.inventory import InventoryFile

    with open(root / "objects.inv", "rb") as fh:
        inv = InventoryFile.load(fh, "", lambda base, uri: uri)
    documented = {name for entries in inv.values() for name in entries}
    problems = []
    for package in mvtk_docs.API_PACKAGES:
        modname = f"mvtk.{package}"
        try:
            module = importlib.import_module(modname)
        except ModuleNotFoundError:
            continue
        for name in getattr(module, "__all__", []):
            obj = getattr(module, name)
            home = mvtk_docs._home_package(obj) or modname
            if f"{modname}.{name}" in documented or f"{home}.{name}" in documented:
                continue
            if getattr(obj, "__name__", None) and f"{obj.__module__}.{obj.__name__}" in documented:
                continue
            problems.append(f"API reference: {modname}.{name} is public (__all__) but "
                            "not documented")
    return problems


def screenshot(site: Path, png: Path) -> Path | None:
    """A 1400 x 1800 px screenshot of the site's first page with headless Chromium.

    Returns None (and says why) when no Chromium is installed: the screenshot is an
    artifact for people, not a check.
    """
    import shutil
    import subprocess
    import tempfile

    exe = next((shutil.which(n) for n in ("chromium", "chromium-browser", "google-chrome")
                if shutil.which(n)), None)
    if exe is None:
        print("check_site: no chromium on PATH; no screenshot taken")
        return None
    png.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as profile:
        cmd = [exe, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
               "--no-first-run", "--disable-background-networking",
               "--disable-component-update", "--disable-sync", f"--user-data-dir={profile}",
               "--window-size=1400,1800", f"--screenshot={png}",
               (site / "index.html").resolve().as_uri()]
        subprocess.run(cmd, capture_output=True, timeout=120, check=False)
    if not png.is_file():
        print(f"check_site: chromium wrote no screenshot to {png}")
        return None
    print(f"check_site: screenshot of the first page: {png}")
    return png


#: pages a reader looks for first; and the least number of pictures the landing page
#: and the gallery must show (FRF, decay, mode shapes, controller responses, MAC, ...)
REQUIRED_PAGES = ("install.html", "getting_started.html", "help.html",
                  "guide/overview.html")
MIN_LANDING_IMAGES = 2
MIN_GALLERY_IMAGES = 6


def _images(path: Path) -> int:
    return sum(1 for link in _parse(path).links
               if link.startswith("data:image") or "_images/" in link)


def check_pictures(root: Path) -> list[str]:
    """Missing reader pages, and a landing page or gallery without its figures (a
    gallery notebook that found its data draws at least one figure)."""
    problems = [f"{p}: page missing" for p in REQUIRED_PAGES if not (root / p).is_file()]
    n = _images(root / "index.html")
    if n < MIN_LANDING_IMAGES:
        problems.append(f"index.html: {n} pictures, expected at least {MIN_LANDING_IMAGES}")
    total = 0
    for page in sorted((root / "gallery").glob("*.html")):
        k = _images(page)
        total += k
        text = page.read_text(encoding="utf-8", errors="replace")
        skipped = "NOT FOUND" in text or "data: None" in text
        if k == 0 and not skipped:
            problems.append(f"gallery/{page.name}: no figure")
    if total < MIN_GALLERY_IMAGES:
        problems.append(f"gallery: {total} figures in all, expected at least "
                        f"{MIN_GALLERY_IMAGES}")
    return problems


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("site", type=Path, help="built HTML folder (docs/_build/html)")
    parser.add_argument("--external", action="store_true", help="list external links")
    parser.add_argument("--screenshot", type=Path, default=None,
                        help="also save a PNG of the first page (needs chromium)")
    args = parser.parse_args(argv)
    if not (args.site / "index.html").is_file():
        print(f"check_site: {args.site} has no index.html; build the docs first",
              file=sys.stderr)
        return 2
    problems, external = check_links(args.site)
    problems += check_api(args.site)
    problems += check_pictures(args.site)
    if args.external:
        print("\n".join(external))
    for p in problems:
        print(p, file=sys.stderr)
    if args.screenshot is not None:
        screenshot(args.site, args.screenshot)
    n_pages = sum(1 for _ in args.site.rglob("*.html"))
    print(f"check_site: {n_pages} pages, {len(problems)} problem(s), "
          f"{len(external)} external link(s) not followed")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
