"""surface stage."""
