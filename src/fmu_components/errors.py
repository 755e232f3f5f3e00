"""The error every command raises for a mistake the user can fix: one line that says what to
do. The command line prints it and exits with status 2, without a traceback."""


class UsageError(Exception):
    """A mistake on the user's side, said in one line with what to do about it."""
