"""numba's on-disk cache (``cache=True``) is invalidated when the file of the compiled function changes, not when a
compiled function it calls from another module does (numba's documented limitation). So every module with cached
kernels that imports another crowdbench module with kernels carries, per such dependency, a line
``# numba-cache-key: <module> <first 12 hex digits of the SHA-256 of that module's source>``. This test fails when a
dependency changed and the key was not updated; updating the key changes the dependent's own source, which
invalidates its cache — and, through its own key line in its dependents, theirs.
``python tests/test_numba_cache_keys.py`` brings the key lines up to date."""

from __future__ import annotations

import ast
import hashlib
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1] / "crowdbench"
KEY = re.compile(r"^# numba-cache-key: (\S+) ([0-9a-f]{12})$", re.M)


def module_path(name: str, root: Path = ROOT) -> Path | None:
    rel = Path(*name.split("."))
    for p in (root.parent / rel.with_suffix(".py"), root.parent / rel / "__init__.py"):
        if p.exists():
            return p
    return None


def has_kernels(path: Path) -> bool:
    return "njit" in path.read_text()


def kernel_dependencies(path: Path, root: Path = ROOT) -> set[str]:
    """crowdbench modules with kernels that ``path`` imports (module level or inside functions)."""
    deps = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("crowdbench"):
            dep = module_path(node.module, root)
            if dep is not None and dep != path and has_kernels(dep):
                deps.add(node.module)
    return deps


def expected_keys(root: Path = ROOT) -> dict[Path, dict[str, str]]:
    """Per module with cached kernels under ``root``: dependency → the key it must carry."""
    out = {}
    for path in sorted(root.rglob("*.py")):
        text = path.read_text()
        if "cache=True" not in text:
            continue
        out[path] = {dep: hashlib.sha256(module_path(dep, root).read_bytes()).hexdigest()[:12]
                     for dep in kernel_dependencies(path, root)}
    return out


def stale(root: Path = ROOT) -> list[str]:
    """The modules whose key lines are not what :func:`expected_keys` wants, with the lines they need."""
    wrong = []
    for path, want in expected_keys(root).items():
        if dict(KEY.findall(path.read_text())) != want:
            lines = "\n".join(f"# numba-cache-key: {m} {d}" for m, d in sorted(want.items()))
            wrong.append(f"{path.relative_to(root.parent)} must carry exactly:\n{lines or '(no key lines)'}")
    return wrong


def test_cached_kernels_carry_the_digest_of_every_kernel_module_they_import():
    wrong = stale()
    assert not wrong, ("numba's cache does not follow imports; update the key lines (this changes the module, "
                       "so its cached kernels recompile):\n" + "\n".join(wrong))


def test_the_check_sees_a_changed_dependency(tmp_path):
    """In a copy of the package, an edit of ``spatial.py`` alone makes its direct dependents stale."""
    import shutil

    copy = tmp_path / "crowdbench"
    shutil.copytree(ROOT, copy, ignore=shutil.ignore_patterns("__pycache__", "*.pt", "*.npz"))
    assert not stale(copy)
    with open(copy / "spatial.py", "a") as f:
        f.write("\n# an edit\n")
    wrong = "\n".join(stale(copy))
    assert "crowdbench/humans/orca_kernel.py" in wrong and "crowdbench/geometry.py" in wrong


def write_keys() -> None:
    """Rewrite every module's key lines (before its ``from __future__`` import) until they are all current."""
    for _ in range(20):  # a dependency's new key changes its digest: repeat until stable (the imports form a DAG)
        changed = False
        for path, want in expected_keys().items():
            text = path.read_text()
            if dict(KEY.findall(text)) == want:
                continue
            text = re.sub(r"# numba-cache-key: [^\n]+\n", "", text)
            lines = "".join(f"# numba-cache-key: {m} {d}\n" for m, d in sorted(want.items()))
            head = "\n\n" + lines + ("\n" if lines else "") + "from __future__ import annotations\n"
            text = re.sub(r"\n+from __future__ import annotations\n", head, text, count=1)
            path.write_text(text)
            changed = True
        if not changed:
            return
    raise RuntimeError("numba cache keys did not settle")


if __name__ == "__main__":  # python tests/test_numba_cache_keys.py: bring the key lines up to date
    write_keys()
