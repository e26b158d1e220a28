"""The communication manager's language: verbalization, referring expressions, requests."""
