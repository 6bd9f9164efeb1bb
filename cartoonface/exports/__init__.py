"""What a generated face is exported as besides its pages: mouth cues (cues.py), captions (captions.py)."""
