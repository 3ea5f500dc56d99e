"""The dispatcher's pages: the case list and the case page (HTML), in the pages' frame
(``service.page_frame``; signing in: ``service.sign_in``)."""
