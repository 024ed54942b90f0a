"""The service's OpenAPI document, as shipped in docs/openapi.json (a test keeps it current):

python -m tmpnav.serve.openapi > docs/openapi.json
"""

from __future__ import annotations

import json
from types import SimpleNamespace
from typing import Any, cast


def document() -> dict[str, Any]:
    """The OpenAPI document of the routes (no site is loaded: the routes are only described)."""
    from tmpnav.serve.app import create_app
    from tmpnav.serve.service import Limits, Service

    app = create_app(cast(Service, SimpleNamespace(limits=Limits())))
    return app.openapi()


def text() -> str:
    return json.dumps(document(), indent=2, sort_keys=True) + "\n"


if __name__ == "__main__":
    print(text(), end="")
