"""The live view's page, script and style sheet, served by tmpnav.serve.app (no library, nothing
fetched at run time)."""
