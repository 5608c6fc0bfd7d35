"""Method ``splitsum``: prefiltered GGX and the DFG table, Karis 2013 (method, dfg, plugin)."""
