"""Cross-code validation: the same scenes built in other codes (MoorDyn-C v2) and compared with ours."""
