"""JSON Schemas of the files users write (shipped so that editors can use them)."""
