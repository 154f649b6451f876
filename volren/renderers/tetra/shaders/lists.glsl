// The per-pixel entry lists: u_slots candidates per pixel, in one buffer, and a count per pixel
// (`gl_walk.py`). A list that overflows is only counted: the host sees `most` > u_slots, grows
// the slots and bins again. (Fixed slots instead of linked lists: appending contends only per
// pixel, not on one global counter, and the walk reads a pixel's candidates side by side.)

#ifndef LIST_ACCESS
#define LIST_ACCESS coherent
#endif

layout(std430, binding = 4) LIST_ACCESS buffer Counts { uint counts[]; };  // per pixel: candidates appended
layout(std430, binding = 5) LIST_ACCESS buffer Slots { uint slots[]; };    // u_slots per pixel
layout(std430, binding = 6) buffer Counters {
    uint most;    // the longest list, when longer than u_slots (else 0)
    uint padding[3];
    // per lane: cells walked through, cell segments integrated, walks stopped at u_max_steps, rays
    // with at least one cell step; invocations add to one of STAT_LANES lanes, so that a million
    // rays do not queue on four addresses (the host sums the lanes)
    uvec4 work[];
} counters;

const uint STAT_LANES = 1024u;


// A candidate is cell * 8 + code: code 0-3 names the boundary face the ray may enter through, NEAR_CELL
// a cell the near plane cuts (the ray may start inside it).
const uint NEAR_CELL = 4u;

uniform uint u_slots;  // candidates a pixel's list holds

#if !defined(LISTS_READ_ONLY)
void append(uint pixel, uint candidate) {
    uint i = atomicAdd(counts[pixel], 1u);
    if (i < u_slots) slots[pixel * u_slots + i] = candidate;
    else atomicMax(counters.most, i + 1u);
}
#endif
