"""Learned planners repeat across x86 machines: importing mrexplore pins Intel MKL's code path (MKL_CBWR)."""

from __future__ import annotations

import os
import subprocess
import sys

_PRODUCT = (
    "import hashlib, torch; g = torch.Generator().manual_seed(0); "
    "a = torch.randn(97, 301, generator=g); b = torch.randn(301, 45, generator=g); "
    "print(hashlib.sha256((a @ b).numpy().tobytes()).hexdigest())"
)


def _python(code: str, mkl_cbwr: str | None) -> str:
    env = {k: v for k, v in os.environ.items() if k != "MKL_CBWR"}
    if mkl_cbwr is not None:
        env["MKL_CBWR"] = mkl_cbwr
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    return done.stdout.strip()


def test_importing_the_package_pins_mkl_to_its_compatible_path() -> None:
    assert _python("import os, mrexplore; print(os.environ['MKL_CBWR'])", None) == "COMPATIBLE"


def test_a_path_the_user_chose_is_kept() -> None:
    assert _python("import os, mrexplore; print(os.environ['MKL_CBWR'])", "AUTO") == "AUTO"


def test_torch_products_after_the_import_take_the_pinned_path() -> None:
    # On an AVX-512 CPU MKL's own choice rounds this product otherwise (it did on the 2-core machine).
    assert _python("import mrexplore; " + _PRODUCT, None) == _python(_PRODUCT, "COMPATIBLE")
