; The room domain of the paper (Thomas, Mastrogiovanni, Baglietto, Fig. "A fragment of
; the PDDL room domain"), as ENHSP can read it.
;
; Differences from the paper's figure, and why:
; - ENHSP has no durative actions: goto_room is instantaneous and adds the cost computed
;   by the motion planner (the semantic attachment) to the metric act-cost, as the
;   paper's "(at end (increase (act-cost) (external)))" does.
; - The cost is a static function (pair-cost ...) filled in from tmpnav's cost oracle
;   before planning, because ENHSP cannot call back into tmpnav during search; the
;   paper's "triggered" fluent only served that call-back and is dropped.
; - (connected ?from ?to) becomes (can_move ?r ?from ?to): the robot must be able to
;   drive there (the oracle found a roadmap path); and the two robots must differ.
; - Per-robot goals (the paper's Fig. 2: r must visit L10) need (visited_by ?r ?l); it is
;   recorded only for a robot's target rooms, so it adds no states the paper did not have.
; Both robots of the pair move, each to a room: an odd number of rooms to visit forces
; an extra visit (the paper's own remark in its Conclusion).
(define (domain rooms-paper)
  (:requirements :typing :numeric-fluents :negative-preconditions :equality :conditional-effects)
  (:types robot location)
  (:predicates
    (robot_in ?r - robot ?l - location)
    (can_move ?r - robot ?from ?to - location)
    (target ?r - robot ?l - location)
    (visited ?l - location)
    (visited_by ?r - robot ?l - location))
  (:functions
    (act-cost)
    (pair-cost ?r1 - robot ?from1 ?to1 - location ?r2 - robot ?from2 ?to2 - location))
  (:action goto_room
    :parameters (?r1 - robot ?from1 ?to1 - location ?r2 - robot ?from2 ?to2 - location)
    :precondition (and (not (= ?r1 ?r2))
                       (robot_in ?r1 ?from1) (can_move ?r1 ?from1 ?to1)
                       (robot_in ?r2 ?from2) (can_move ?r2 ?from2 ?to2))
    :effect (and (not (robot_in ?r1 ?from1)) (not (robot_in ?r2 ?from2))
                 (robot_in ?r1 ?to1) (robot_in ?r2 ?to2)
                 (visited ?to1) (visited ?to2)
                 (when (target ?r1 ?to1) (visited_by ?r1 ?to1)) (when (target ?r2 ?to2) (visited_by ?r2 ?to2))
                 (increase (act-cost) (pair-cost ?r1 ?from1 ?to1 ?r2 ?from2 ?to2))))
)
