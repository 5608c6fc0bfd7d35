"""Method ``parallax``: parallax-corrected cube maps, Lagarde & Zanuttini 2012 (method, plugin)."""
