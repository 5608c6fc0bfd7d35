"""CPU prefiltering of environments: brute-force integrals (the independent references)."""
