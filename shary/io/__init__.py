"""Reading and checking the files users write (sismic's split: io apart from model and engine)."""
