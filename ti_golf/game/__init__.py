"""The golf game (report §2.5, ``ti-golf play``): its rules and rounds (:mod:`.rules`), the cup's
capture rule (:mod:`.cup`), the course map of a round (:mod:`.course_map`) and the GGUI window
(:mod:`.window`)."""
