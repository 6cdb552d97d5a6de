"""Validation of anklelab against variation: generators and accuracy studies (not shipped)."""
