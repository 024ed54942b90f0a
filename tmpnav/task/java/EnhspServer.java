// ENHSP's searches for one tmpnav run, in a JVM of their own (tmpnav/task/enhsp_jvm.py starts
// it as `java ... -cp tmpnav-enhsp.jar tmpnav.EnhspServer <enhsp.jar>` and talks to it through
// its standard input and output). Built into the jar beside it by `make java`.
//
// Why a process and not the JVM inside tmpnav (JPype, until 2026-11-28): starting an in-process
// JVM held the run's main thread for 0.2 s in every fresh `tmpnav plan` (JPype's start makes
// thousands of calls between Python and Java, each taking Python's lock), and every call into
// it from a searching thread waited for that lock while the main thread computed costs. This
// process starts in 0.04 s beside tmpnav's own start, makes its searches ready while tmpnav
// loads its modules and grows its roadmap, and ends when tmpnav does (its input closes).
package tmpnav;

import java.io.BufferedReader;
import java.io.FileDescriptor;
import java.io.FileOutputStream;
import java.io.InputStreamReader;
import java.io.OutputStream;
import java.io.PrintStream;
import java.lang.reflect.InvocationTargetException;
import java.lang.reflect.Method;
import java.nio.charset.StandardCharsets;
import java.util.ArrayDeque;
import java.util.Arrays;
import java.util.Map;
import java.util.concurrent.ConcurrentHashMap;
import java.util.concurrent.atomic.AtomicInteger;

/**
 * The server: one line per request on standard input, one line per answer on standard output,
 * fields separated by tabs.
 *
 * <pre>
 * solve  ID  MILLISECONDS  ARG...   ENHSP's main(ARG...) in a slot, stopped after MILLISECONDS
 *                                   -> done ID ok | done ID error TEXT | done ID timeout
 *                                      | done ID stuck (past its limit, and this Java cannot
 *                                        stop a thread: Java 20+; the caller ends this process)
 * warm   COUNT  MILLISECONDS  ARG...  COUNT slots ready in all (idle or being made), each new
 *                                   one having run main(ARG...) once, stopped after
 *                                   MILLISECONDS                              -> warmed
 * stop   ID | *                     stop that search (every search): it answers done ID timeout
 * (end of input)                    the process ends at once, whatever runs
 * </pre>
 *
 * <p>It says {@code ready} once it reads requests. ENHSP's own output (its log, on
 * System.out and System.err) goes nowhere: the answers have the process's standard output to
 * themselves. Each search runs in a slot of its own ({@link EnhspSlot}), its static state put
 * back first; slots are kept for the next searches.
 */
public final class EnhspServer {
    /** milliseconds a stopped search has to end before this process is given up */
    private static final long STOP_GRACE_MS = 2000;

    private final String jar;
    private final PrintStream answers;
    private final ArrayDeque<EnhspSlot> idle = new ArrayDeque<>();
    private int warming; // slots being made ready by warm requests
    private final AtomicInteger warmed = new AtomicInteger(); // warm searches started: their ids
    private final Map<String, Thread> searches = new ConcurrentHashMap<>();
    private final Map<String, Boolean> stopped = new ConcurrentHashMap<>();

    private EnhspServer(String jar, PrintStream answers) {
        this.jar = jar;
        this.answers = answers;
    }

    public static void main(String[] args) throws Exception {
        PrintStream answers = new PrintStream(new FileOutputStream(FileDescriptor.out), true, StandardCharsets.UTF_8);
        PrintStream nowhere = new PrintStream(OutputStream.nullOutputStream());
        System.setOut(nowhere); // ENHSP's log
        System.setErr(nowhere);
        EnhspServer server = new EnhspServer(args[0], answers);
        server.answer("ready");
        BufferedReader requests = new BufferedReader(new InputStreamReader(System.in, StandardCharsets.UTF_8));
        String line;
        while ((line = requests.readLine()) != null) {
            server.handle(line.split("\t", -1));
        }
        Runtime.getRuntime().halt(0); // tmpnav has ended (or closed its end): so does every search
    }

    private synchronized void answer(String... fields) {
        answers.println(String.join("\t", fields));
    }

    private void handle(String[] request) {
        switch (request[0]) {
            case "solve":
                solve(request[1], Long.parseLong(request[2]), Arrays.copyOfRange(request, 3, request.length));
                break;
            case "warm":
                warm(Integer.parseInt(request[1]), Long.parseLong(request[2]), Arrays.copyOfRange(request, 3, request.length));
                break;
            case "stop":
                for (Map.Entry<String, Thread> search : searches.entrySet()) {
                    if (request[1].equals("*") || request[1].equals(search.getKey())) {
                        stop(search.getKey(), search.getValue());
                    }
                }
                break;
            default:
                throw new IllegalArgumentException("unknown request " + request[0]);
        }
    }

    /** Run ENHSP in a slot in a thread of its own, watched for its time limit by another. */
    private void solve(String id, long milliseconds, String[] args) {
        start(id, milliseconds, () -> {
            String[] outcome = run(id, args, false);
            if (stopped.remove(id) == null) {
                answer(outcome[0].equals("ok") ? new String[] {"done", id, "ok"} : new String[] {"done", id, "error", outcome[1]});
            }
        });
    }

    private void start(String id, long milliseconds, Runnable work) {
        Thread search = new Thread(work, "tmpnav-search-" + id);
        search.setDaemon(true);
        searches.put(id, search);
        Thread watch = new Thread(() -> {
            try {
                search.join(milliseconds);
                if (search.isAlive()) {
                    stop(id, search);
                }
            } catch (InterruptedException err) {
                Thread.currentThread().interrupt();
            } finally {
                searches.remove(id);
            }
        }, "tmpnav-watch-" + id);
        watch.setDaemon(true);
        search.start();
        watch.start();
    }

    /** Stop a search (Thread.stop): "timeout" once it has ended, "stuck" if it cannot be stopped. */
    @SuppressWarnings({"deprecation", "removal"})
    private void stop(String id, Thread search) {
        if (stopped.putIfAbsent(id, Boolean.TRUE) != null) {
            return; // already being stopped
        }
        try {
            search.stop(); // Java 17-19; Java 20+ throws UnsupportedOperationException
            search.join(STOP_GRACE_MS);
        } catch (UnsupportedOperationException err) {
            // cannot be stopped: said below
        } catch (InterruptedException err) {
            Thread.currentThread().interrupt();
        }
        if (!id.startsWith("warm-")) {
            answer("done", id, search.isAlive() ? "stuck" : "timeout");
        }
    }

    /** main(args) in an idle slot (a new one if none, or if {@code fresh}): {"ok"} or {"error", text}. */
    private String[] run(String id, String[] args, boolean fresh) {
        EnhspSlot slot;
        try {
            slot = fresh ? EnhspSlot.forEnhsp(jar) : take();
        } catch (Throwable err) {
            return new String[] {"error", describe(err)};
        }
        try {
            slot.reset();
            Method main = slot.load("main").getMethod("main", String[].class);
            main.invoke(null, (Object) args);
            give(slot);
            return new String[] {"ok"};
        } catch (InvocationTargetException err) {
            Throwable cause = err.getCause() != null ? err.getCause() : err;
            if (stopped.containsKey(id)) { // stopped inside ENHSP: its state is not known
                close(slot);
            } else {
                give(slot); // ENHSP failed on this problem; its state is put back before the next
            }
            return new String[] {"error", describe(cause)};
        } catch (Throwable err) { // stopped at its time limit (ThreadDeath), or a slot that broke
            close(slot);
            return new String[] {"error", describe(err)};
        }
    }

    private static String describe(Throwable err) {
        String text = err.getClass().getName() + (err.getMessage() != null ? ": " + err.getMessage() : "");
        return text.replace('\t', ' ').replace('\n', ' ').replace('\r', ' ');
    }

    /** An idle slot; while a warm request is making slots, the next one it makes; else a new one. */
    private EnhspSlot take() throws Exception {
        synchronized (idle) {
            while (idle.isEmpty() && warming > 0) {
                idle.wait();
            }
            if (!idle.isEmpty()) {
                return idle.pop();
            }
        }
        return EnhspSlot.forEnhsp(jar);
    }

    private void give(EnhspSlot slot) {
        if (!slot.reusable()) {
            close(slot);
            return;
        }
        synchronized (idle) {
            idle.push(slot);
            idle.notifyAll();
        }
    }

    private static void close(EnhspSlot slot) {
        try {
            slot.close();
        } catch (Exception err) {
            // a loader that does not close holds some memory until the process ends
        }
    }

    /**
     * Slots made ready for the searches to come, one after another (side by side they took
     * both cores while tmpnav grew its roadmap: a fresh 10-room run 0.15 s slower), a search
     * that finds no idle slot meanwhile waiting for the next: {@code warmed} once all have run
     * the sample, or failed to (a slot is good still: its state is put back first).
     */
    private void warm(int count, long milliseconds, String[] args) {
        int missing;
        synchronized (idle) {
            missing = Math.max(count - idle.size() - warming, 0);
            warming += missing;
        }
        if (missing == 0) {
            answer("warmed");
            return;
        }
        warmNext(missing, milliseconds, args);
    }

    /** The next of {@code remaining} slots made and warmed, then the one after it. */
    private void warmNext(int remaining, long milliseconds, String[] args) {
        String id = "warm-" + warmed.getAndIncrement();
        start(id, milliseconds, () -> {
            try {
                run(id, args, true);
                stopped.remove(id);
            } finally {
                synchronized (idle) {
                    warming -= 1;
                    idle.notifyAll();
                }
                if (remaining > 1) {
                    warmNext(remaining - 1, milliseconds, args);
                } else {
                    answer("warmed");
                }
            }
        });
    }
}
