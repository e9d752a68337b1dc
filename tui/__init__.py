"""The operator console (Textual): shows what the bus says, sends operator commands."""
