"""formulae stage."""
