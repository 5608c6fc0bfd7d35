"""Math and conventions without GL: parameterizations, SH, BRDFs, transforms."""
