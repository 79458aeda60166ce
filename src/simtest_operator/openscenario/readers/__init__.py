"""Element readers: XML elements in, model nodes out (one module per model area)."""
