"""The source distribution a user would install: built from python/ with maturin, installed with pip into
a fresh virtual environment (compiling the Rust crates it carries), imported and stepped there."""

import os
import subprocess
import sys
import tarfile
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def run(*args, **kwargs):
    subprocess.run(args, check=True, **kwargs)


def test_the_sdist_builds_installs_and_runs_in_a_fresh_environment(tmp_path):
    # maturin, the package's build backend, builds the sdist (pip's isolated build installs it anew).
    run(sys.executable, "-m", "pip", "install", "--quiet", "--disable-pip-version-check", "maturin>=1.9,<2")
    manifest = str(ROOT / "python/Cargo.toml")
    run(sys.executable, "-m", "maturin", "sdist", "-m", manifest, "-o", str(tmp_path))
    (sdist,) = tmp_path.glob("anima-*.tar.gz")
    with tarfile.open(sdist) as t:
        names = {Path(n).name for n in t.getnames() if n.count("/") == 1}
    assert {"LICENSE-MIT", "LICENSE-APACHE", "README.md", "pyproject.toml"} <= names, names

    env_dir = tmp_path / "env"
    venv.create(env_dir, with_pip=True)
    python = env_dir / "bin" / "python"
    # The workspace's target folder keeps the compiled dependencies between runs; the anima crates are
    # compiled from the sdist's own copies.
    target = os.environ.get("CARGO_TARGET_DIR", str(ROOT / "target"))
    env = {**os.environ, "CARGO_TARGET_DIR": target}
    run(str(python), "-m", "pip", "install", "--quiet", "--disable-pip-version-check", str(sdist), env=env)
    check = (
        "import anima, importlib.metadata as m\n"
        "c = anima.Cloth.sheet(n=8); c.step(10); assert c.steps == 10 and c.positions.shape == (64, 3)\n"
        "files = {f.name for f in m.files('anima')}\n"
        "assert {'LICENSE-MIT', 'LICENSE-APACHE'} <= files, files\n"
    )
    # Run outside the repository, so that nothing but the installed package can be imported.
    run(str(python), "-c", check, cwd=tmp_path)
