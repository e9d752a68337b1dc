"""Jobs: submissions, moderation, queue, assignment, fleet presence, persistence, recording."""
