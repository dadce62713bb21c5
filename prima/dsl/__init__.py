"""PXML documents and robot profiles: secure loading, schemas, meaning checks."""
