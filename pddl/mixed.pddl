; tmpnav's default "mixed" encoding: single-robot moves, plus paired moves where two
; robots drive at the same time and observe each other.
;
; This file holds the single-robot action, the same as in single.pddl. The paired moves
; are generated per problem: one parameterless action per cooperative pair,
; "goto_room_pair__<r1>__<from1>__<to1>__<r2>__<from2>__<to2>", whose cost is the
; oracle's joint cost, only where that joint cost is strictly lower than the two single
; moves done one after the other (any other pair is dominated by two single moves, so
; leaving it out keeps the plan optimal for the table). Grounded pair actions keep the
; problem small: a 6-ary cost function would be written out for every combination of its
; arguments. Robots that do not move in an action stay where they are and take no part
; in its observations.
(define (domain rooms-mixed)
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
