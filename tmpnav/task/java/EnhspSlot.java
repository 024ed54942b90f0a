// ENHSP in a class loader of its own, its static state recorded and put back before every
// search: a "slot" of EnhspServer (tmpnav/task/enhsp_jvm.py starts that server). Built into the
// jar beside it by `make java` (javac --release 17); tests/task/test_enhsp_slot_jar.py checks
// that the jar was built from these sources.
package tmpnav;

import java.io.File;
import java.io.IOException;
import java.lang.reflect.Field;
import java.lang.reflect.Modifier;
import java.net.URL;
import java.net.URLClassLoader;
import java.util.ArrayList;
import java.util.Collection;
import java.util.Enumeration;
import java.util.HashMap;
import java.util.List;
import java.util.Map;
import java.util.jar.JarFile;

/**
 * ENHSP over {@code enhsp.jar} in a class loader of its own, and the first values of its static
 * fields, put back by {@link #reset()} before every solve.
 *
 * <p>ENHSP keeps registries in static fields (interned predicates, fluents, objects, types,
 * transition ids) and never resets them. {@link #record} loads and initialises classes, in the
 * order of their archive, and keeps each static field that it can put back: a collection or map
 * (the same object, its first contents), or a non-final field holding null, a primitive or a
 * string. A static field of any other kind makes the slot not {@link #reusable()}: it then
 * serves one solve only.
 */
public final class EnhspSlot {
    private final URLClassLoader loader;
    private final List<Field> fields = new ArrayList<>();
    private final List<Object> values = new ArrayList<>();
    /** a copy of each collection's or map's first contents; null for a plain value */
    private final List<Object> contents = new ArrayList<>();
    private boolean reusable = true;

    /** A class loader over {@code jar} (its manifest's Class-Path included), below the platform's. */
    public EnhspSlot(String jar) throws IOException {
        URL url = new File(jar).toURI().toURL();
        loader = new URLClassLoader(new URL[] {url}, ClassLoader.getPlatformClassLoader());
    }

    /**
     * A slot for ENHSP's {@code enhsp.jar}: its main class loaded first, then ENHSP's own
     * classes recorded, those of enhsp.jar and of its PDDL library (libs/JPddl_.jar), whose
     * static fields hold its state; the other libraries are generic (collections, parser
     * runtime).
     */
    public static EnhspSlot forEnhsp(String jar) throws Exception {
        EnhspSlot slot = new EnhspSlot(jar);
        slot.load("main");
        slot.record(jar, new String[] {"main.", "planners/"});
        String library = new File(new File(new File(jar).getParentFile(), "libs"), "JPddl_.jar").getPath();
        slot.record(library, new String[] {"com/hstairs/"});
        return slot;
    }

    /** The loader's class {@code name}, initialised. */
    public Class<?> load(String name) throws ClassNotFoundException {
        return Class.forName(name, true, loader);
    }

    /**
     * Load and initialise every class of {@code archive} whose path starts with one of
     * {@code prefixes} ("planners/", "main."), and record its static fields. A class that
     * cannot load here is not used here either: skipped.
     */
    public void record(String archive, String[] prefixes) throws IOException {
        try (JarFile jar = new JarFile(archive)) {
            Enumeration<? extends java.util.zip.ZipEntry> entries = jar.entries();
            while (entries.hasMoreElements()) {
                String path = entries.nextElement().getName();
                if (path.endsWith(".class") && startsWithAny(path, prefixes)) {
                    recordClass(path.substring(0, path.length() - ".class".length()).replace('/', '.'));
                }
            }
        }
    }

    private static boolean startsWithAny(String path, String[] prefixes) {
        for (String prefix : prefixes) {
            if (path.startsWith(prefix)) {
                return true;
            }
        }
        return false;
    }

    private void recordClass(String name) {
        Field[] declared;
        try {
            declared = load(name).getDeclaredFields();
        } catch (Throwable err) { // LinkageError, ClassNotFoundException: not used here either
            return;
        }
        for (Field field : declared) {
            int modifiers = field.getModifiers();
            if (!Modifier.isStatic(modifiers)) {
                continue;
            }
            Object value;
            try {
                field.setAccessible(true);
                value = field.get(null);
            } catch (Throwable err) { // a field it cannot read, it cannot put back
                reusable = false;
                continue;
            }
            if (value instanceof Collection) {
                keep(field, value, new ArrayList<Object>((Collection<?>) value));
            } else if (value instanceof Map) {
                keep(field, value, new HashMap<Object, Object>((Map<?, ?>) value));
            } else if (Modifier.isFinal(modifiers)) {
                continue; // constants (ENHSP's final objects are its true and false predicates)
            } else if (value == null || field.getType().isPrimitive() || value instanceof String) {
                keep(field, value, null);
            } else {
                reusable = false; // state this class does not know how to put back
            }
        }
    }

    private void keep(Field field, Object value, Object firstContents) {
        fields.add(field);
        values.add(value);
        contents.add(firstContents);
    }

    /** ENHSP's static fields as they were when their classes were recorded. */
    @SuppressWarnings("unchecked")
    public void reset() throws IllegalAccessException {
        for (int i = 0; i < fields.size(); i++) {
            Field field = fields.get(i);
            Object value = values.get(i);
            Object first = contents.get(i);
            if (first instanceof Map) {
                Map<Object, Object> map = (Map<Object, Object>) value;
                map.clear();
                map.putAll((Map<Object, Object>) first);
            } else if (first != null) {
                Collection<Object> collection = (Collection<Object>) value;
                collection.clear();
                collection.addAll((Collection<Object>) first);
            }
            if (!Modifier.isFinal(field.getModifiers())) {
                field.set(null, value);
            }
        }
    }

    /** Whether every static field is of a kind {@link #reset()} puts back. */
    public boolean reusable() {
        return reusable;
    }

    /** The static fields {@link #reset()} puts back, each as "class.field". */
    public String[] recorded() {
        String[] names = new String[fields.size()];
        for (int i = 0; i < names.length; i++) {
            names[i] = fields.get(i).getDeclaringClass().getName() + "." + fields.get(i).getName();
        }
        return names;
    }

    public void close() throws IOException {
        loader.close();
    }
}
