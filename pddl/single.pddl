; One goto_room action per robot: tmpnav's "single" encoding.
; Robots move one at a time; the cost of a move is the oracle's single-robot cost (no
; mutual observations, since no other robot moves at the same time). A robot moves only
; into a room no robot has visited yet, or into one of its own target rooms that it has
; not visited itself: every other move would visit nothing new.
(define (domain rooms-single)
  (:requirements :typing :numeric-fluents :negative-preconditions :disjunctive-preconditions :conditional-effects)
  (:types robot location)
  (:predicates
    (robot_in ?r - robot ?l - location)
    (can_move ?r - robot ?from ?to - location)
    (target ?r - robot ?l - location)
    (visited ?l - location)
    (visited_by ?r - robot ?l - location))
  (:functions
    (act-cost)
    (move-cost ?r - robot ?from ?to - location))
  (:action goto_room
    :parameters (?r - robot ?from ?to - location)
    :precondition (and (robot_in ?r ?from) (can_move ?r ?from ?to)
                       (or (not (visited ?to)) (and (target ?r ?to) (not (visited_by ?r ?to)))))
    :effect (and (not (robot_in ?r ?from)) (robot_in ?r ?to) (visited ?to)
                 (when (target ?r ?to) (visited_by ?r ?to))
                 (increase (act-cost) (move-cost ?r ?from ?to))))
)
