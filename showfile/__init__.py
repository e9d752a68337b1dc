"""Show files: YAML validated once at start into typed objects; errors name file, line and field."""
