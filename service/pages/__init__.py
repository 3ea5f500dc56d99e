"""The dispatcher's pages: the case list and the case page (HTML), and their sign-in."""
