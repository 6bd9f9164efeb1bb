"""A cartoon face model from a portrait photo: landmarks, the named points, hair and colours (docs/photo.md)."""
