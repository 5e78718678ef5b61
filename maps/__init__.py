"""Map data shipped with socialzoo (installed as the package socialzoo._maps)."""
